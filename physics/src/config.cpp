#include "canhil/physics/config.hpp"
#include "canhil/physics/config_toml.hpp"

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <set>
#include <sstream>

#include "canhil/base/spelling.hpp"

namespace canhil::physics {
namespace {

int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  // min excluded
  std::string describe() const {
    std::ostringstream os;
    if (std::isinf(max)) {
      os << "must be " << (min_open ? "greater than " : "at least ") << min;
    } else {
      os << "must be between " << min << " and " << max;
    }
    return os.str();
  }
  bool contains(double v) const { return (min_open ? v > min : v >= min) && v <= max; }
};
const Range kPositive{0, std::numeric_limits<double>::infinity(), true};
const Range kNonNegative{0, std::numeric_limits<double>::infinity(), false};
Range between(double a, double b) { return Range{a, b, false}; }

// Reads one table: each read() marks its key as known; finish() reports the rest.
class Reader {
 public:
  Reader(const toml::table& table, std::string prefix, const std::string& file)
      : table_(table), prefix_(std::move(prefix)), file_(file) {}

  [[noreturn]] void fail(const toml::node* at, const std::string& key, const std::string& message) const {
    throw ConfigError(file_, at != nullptr ? line_of(*at) : line_of(table_), name(key), message);
  }
  std::string name(const std::string& key) const { return prefix_.empty() ? key : prefix_ + "." + key; }

  void number(const std::string& key, double& out, const Range& range = {}) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    double v = 0;
    if (const auto* f = n->as_floating_point()) {
      v = f->get();
    } else if (const auto* i = n->as_integer()) {
      v = static_cast<double>(i->get());
    } else {
      fail(n, key, "must be a number");
    }
    if (!std::isfinite(v) || !range.contains(v)) {
      std::ostringstream os;
      os << range.describe() << ", got " << v;
      fail(n, key, os.str());
    }
    out = v;
  }
  void integer(const std::string& key, int& out, int min, int max) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    const auto* i = n->as_integer();
    if (i == nullptr) fail(n, key, "must be a whole number");
    if (i->get() < min || i->get() > max) {
      fail(n, key,
           "must be between " + std::to_string(min) + " and " + std::to_string(max) + ", got " +
               std::to_string(i->get()));
    }
    out = static_cast<int>(i->get());
  }
  void unsigned_long(const std::string& key, unsigned long& out) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    const auto* i = n->as_integer();
    if (i == nullptr || i->get() < 0) fail(n, key, "must be a whole number, 0 or more");
    out = static_cast<unsigned long>(i->get());
  }
  void boolean(const std::string& key, bool& out) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    const auto* b = n->as_boolean();
    if (b == nullptr) fail(n, key, "must be true or false");
    out = b->get();
  }
  void numbers(const std::string& key, std::array<double, 3>& out) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    const auto* a = n->as_array();
    if (a == nullptr || a->size() != out.size()) fail(n, key, "must be a list of 3 numbers, e.g. [30, 150, 270]");
    for (std::size_t k = 0; k < out.size(); ++k) {
      const auto v = (*a)[k].value<double>();
      if (!v) fail(n, key, "must be a list of 3 numbers, e.g. [30, 150, 270]");
      out[k] = *v;
    }
  }
  /// A sub-table; absent gives an empty one. Reads it with `body`.
  void table(const std::string& key, const std::function<void(Reader&)>& body) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    static const toml::table kEmpty;
    const toml::table* t = &kEmpty;
    if (n != nullptr) {
      t = n->as_table();
      if (t == nullptr) fail(n, key, "must be a table ([" + name(key) + "])");
    }
    Reader sub(*t, name(key), file_);
    body(sub);
    sub.finish();
  }
  /// An array of tables ([[key]]); calls `body` for each.
  void array_of_tables(const std::string& key, const std::function<void(Reader&)>& body) {
    known_.insert(key);
    const toml::node* n = table_.get(key);
    if (n == nullptr) return;
    const auto* a = n->as_array();
    if (a == nullptr) fail(n, key, "must be a list of tables ([[" + name(key) + "]])");
    for (std::size_t k = 0; k < a->size(); ++k) {
      const auto* t = (*a)[k].as_table();
      if (t == nullptr) fail(n, key, "must be a list of tables ([[" + name(key) + "]])");
      Reader sub(*t, name(key) + "[" + std::to_string(k) + "]", file_);
      body(sub);
      sub.finish();
    }
  }
  /// Marks every key of this table as known (another layer reads them).
  void skip_rest() {
    for (const auto& [k, v] : table_) known_.insert(std::string(k.str()));
  }
  void finish() const {
    for (const auto& [k, v] : table_) {
      const std::string key(k.str());
      if (known_.count(key) != 0) continue;
      const std::string best(nearest_word(key, known_));
      std::string allowed;
      for (const auto& candidate : known_) allowed += (allowed.empty() ? "" : ", ") + candidate;
      fail(&v, key, "unknown field" + (best.empty() ? "" : "; did you mean " + best + "?") + " Known here: " + allowed);
    }
  }

 private:
  const toml::table& table_;
  std::string prefix_;
  const std::string& file_;
  std::set<std::string> known_;
};

void read_rail(Reader& r, RailParams& rail) {
  r.number("full_v", rail.full_v, kPositive);
  r.number("empty_v", rail.empty_v, kPositive);
  r.number("capacity_ah", rail.capacity_ah, kPositive);
  r.number("internal_resistance_ohm", rail.internal_resistance_ohm, kNonNegative);
  r.number("base_current_a", rail.base_current_a, kNonNegative);
  if (rail.empty_v >= rail.full_v) r.fail(nullptr, "empty_v", "must be below full_v");
}

void read_placement(Reader& r, Placement& p) {
  r.number("x_m", p.x_m);
  r.number("y_m", p.y_m);
  r.number("heading_deg", p.heading_deg);
}

void read_all(Reader& root, WorldParams& w) {
  root.table("simulation", [&](Reader& r) {
    auto& s = w.simulation;
    r.number("step_s", s.step_s, between(1e-4, 0.1));
    r.integer("substeps", s.substeps, 1, 100);
    r.number("gravity_mps2", s.gravity_mps2, kNonNegative);
    r.number("cfm", s.cfm, between(0, 1));
    r.number("erp", s.erp, between(0, 1));
    r.boolean("exact_solver", s.exact_solver);
    r.integer("exact_solver_max_rows", s.exact_solver_max_rows, 0, 100000);
    r.integer("solver_iterations", s.solver_iterations, 1, 1000);
    r.integer("sleep_after_steps", s.sleep_after_steps, 0, 1'000'000);
    r.unsigned_long("seed", s.seed);
  });
  root.table("field", [&](Reader& r) {
    auto& f = w.field;
    r.number("length_m", f.length_m, kPositive);
    r.number("width_m", f.width_m, kPositive);
    r.number("line_width_m", f.line_width_m, kPositive);
    r.number("centre_circle_radius_m", f.centre_circle_radius_m, kPositive);
    r.number("goal_area_depth_m", f.goal_area_depth_m, kPositive);
    r.number("goal_area_width_m", f.goal_area_width_m, kPositive);
    r.number("penalty_area_depth_m", f.penalty_area_depth_m, kPositive);
    r.number("penalty_area_width_m", f.penalty_area_width_m, kPositive);
    r.number("corner_arc_radius_m", f.corner_arc_radius_m, kNonNegative);
    r.number("penalty_mark_distance_m", f.penalty_mark_distance_m, kPositive);
    r.number("margin_m", f.margin_m, kNonNegative);
    r.boolean("boundary", f.boundary);
    r.number("boundary_height_m", f.boundary_height_m, kPositive);
    r.number("ground_friction", f.ground_friction, kNonNegative);
    r.table("goal", [&](Reader& g) {
      g.number("width_m", f.goal.width_m, kPositive);
      g.number("height_m", f.goal.height_m, kPositive);
      g.number("depth_m", f.goal.depth_m, kPositive);
      g.number("post_thickness_m", f.goal.post_thickness_m, kPositive);
    });
    if (f.penalty_area_width_m >= f.width_m) r.fail(nullptr, "penalty_area_width_m", "must be less than width_m");
    if (f.goal_area_width_m >= f.penalty_area_width_m) {
      r.fail(nullptr, "goal_area_width_m", "must be less than penalty_area_width_m");
    }
  });
  root.table("ball", [&](Reader& r) {
    auto& b = w.ball;
    r.number("radius_m", b.radius_m, kPositive);
    r.number("mass_kg", b.mass_kg, kPositive);
    r.number("restitution", b.restitution, between(0, 1));
    r.number("bounce_min_speed_mps", b.bounce_min_speed_mps, kNonNegative);
    r.number("friction", b.friction, kNonNegative);
    r.number("rolling_resistance", b.rolling_resistance, kNonNegative);
    r.number("spin_damping", b.spin_damping, kNonNegative);
  });
  root.table("robot", [&](Reader& r) {
    auto& rb = w.robot;
    r.number("body_radius_m", rb.body_radius_m, kPositive);
    r.number("body_height_m", rb.body_height_m, kPositive);
    r.number("body_clearance_m", rb.body_clearance_m, kNonNegative);
    r.number("mouth_width_m", rb.mouth_width_m, kNonNegative);
    r.number("mouth_depth_m", rb.mouth_depth_m, kNonNegative);
    r.number("cone_radius_m", rb.cone_radius_m, kPositive);
    r.number("cone_height_m", rb.cone_height_m, kPositive);
    r.number("cone_top_radius_m", rb.cone_top_radius_m, kPositive);
    r.number("mass_kg", rb.mass_kg, kPositive);
    r.number("wheel_mass_kg", rb.wheel_mass_kg, kPositive);
    r.number("wheel_friction", rb.wheel_friction, kNonNegative);
    r.number("wheel_cross_friction", rb.wheel_cross_friction, kNonNegative);
    r.number("wheel_radius_m", rb.geometry.wheel_radius_m, kPositive);
    r.number("wheel_distance_m", rb.geometry.wheel_distance_m, kPositive);
    r.numbers("wheel_angles_deg", rb.geometry.wheel_angles_deg);
    if (rb.mouth_width_m >= 2 * rb.body_radius_m)
      r.fail(nullptr, "mouth_width_m", "must be less than the body's diameter");
    if (rb.mouth_depth_m >= rb.body_radius_m) r.fail(nullptr, "mouth_depth_m", "must be less than body_radius_m");
    if (rb.geometry.wheel_distance_m >= rb.body_radius_m) {
      r.fail(nullptr, "wheel_distance_m", "must be less than body_radius_m (the wheels are under the body)");
    }
    r.table("encoder", [&](Reader& e) {
      e.integer("pulses_per_rev", rb.encoder.pulses_per_rev, 1, 1'000'000);
      e.integer("quadrature", rb.encoder.quadrature, 1, 4);
      e.number("gear_ratio", rb.encoder.gear_ratio, kPositive);
      e.number("motor_tick_s", rb.encoder.motor_tick_s, kPositive);
    });
    r.table("motor", [&](Reader& m) {
      m.number("terminal_resistance_ohm", rb.motor.terminal_resistance_ohm, kPositive);
      m.number("torque_constant_nm_per_a", rb.motor.torque_constant_nm_per_a, kPositive);
      m.number("gear_efficiency", rb.motor.gear_efficiency, Range{0, 1, true});
      m.number("current_limit_a", rb.motor.current_limit_a, kPositive);
      m.number("rotor_inertia_kgm2", rb.motor.rotor_inertia_kgm2, kNonNegative);
      m.number("stall_speed_radps", rb.motor.stall_speed_radps, kNonNegative);
    });
    r.table("kicker", [&](Reader& k) {
      k.number("lob_angle_deg", rb.kicker.lob_angle_deg, Range{0, 90, true});
      if (rb.kicker.lob_angle_deg >= 90) k.fail(nullptr, "lob_angle_deg", "must be below 90");
      k.number("max_lob_range_m", rb.kicker.max_lob_range_m, kPositive);
      k.integer("max_power", rb.kicker.max_power, 1, 127);
      k.number("full_voltage_v", rb.kicker.full_voltage_v, kPositive);
      k.number("min_fire_voltage_v", rb.kicker.min_fire_voltage_v, kNonNegative);
      k.number("energy_per_full_kick", rb.kicker.energy_per_full_kick, between(0, 1));
      k.number("recharge_time_constant_s", rb.kicker.recharge_time_constant_s, kPositive);
      k.number("grabber_release_s", rb.kicker.grabber_release_s, kNonNegative);
    });
    r.table("barrier", [&](Reader& b) {
      b.number("half_angle_deg", rb.barrier.half_angle_deg, Range{0, 180, true});
      b.number("max_distance_m", rb.barrier.max_distance_m, kPositive);
      b.number("max_height_m", rb.barrier.max_height_m, kPositive);
    });
    r.table("grabber", [&](Reader& g) {
      g.number("range_m", rb.grabber.range_m, kPositive);
      g.number("half_angle_deg", rb.grabber.half_angle_deg, Range{0, 180, true});
      g.number("max_force_n", rb.grabber.max_force_n, kNonNegative);
    });
    r.table("compass", [&](Reader& c) { c.number("north_offset_deg", rb.compass.north_offset_deg); });
    r.table("battery", [&](Reader& b) {
      b.number("initial_charge", rb.battery.initial_charge, between(0, 1));
      b.table("logic", [&](Reader& x) { read_rail(x, rb.battery.logic); });
      b.table("power12", [&](Reader& x) { read_rail(x, rb.battery.power12); });
      b.table("power24", [&](Reader& x) { read_rail(x, rb.battery.power24); });
    });
  });
  root.array_of_tables("robots", [&](Reader& r) {
    Placement p;
    read_placement(r, p);
    w.robots.push_back(p);
  });
  root.array_of_tables("obstacles", [&](Reader& r) {
    ObstaclePlacement o;
    read_placement(r, o.at);
    r.number("radius_m", o.params.radius_m, kPositive);
    r.number("height_m", o.params.height_m, kPositive);
    r.number("mass_kg", o.params.mass_kg, kPositive);
    r.number("friction", o.params.friction, kNonNegative);
    r.boolean("movable", o.params.movable);
    w.obstacles.push_back(o);
  });
  root.table("ball_start", [&](Reader& r) {
    r.number("x_m", w.ball_start.x_m);
    r.number("y_m", w.ball_start.y_m);
    r.number("z_m", w.ball_start.z_m, kPositive);
  });
}

}  // namespace

toml::table parse_toml(std::string_view toml_text, const std::string& file_name) {
  try {
    return toml::parse(toml_text, file_name);
  } catch (const toml::parse_error& e) {
    throw ConfigError(file_name, static_cast<int>(e.source().begin.line), "",
                      std::string("not valid TOML: ") + std::string(e.description()));
  }
}

WorldParams read_world_params(const toml::table& root, const std::string& file_name,
                              const std::vector<std::string>& other_tables) {
  WorldParams w;
  Reader reader(root, "", file_name);
  read_all(reader, w);
  for (const std::string& t : other_tables) {  // another layer's: a [table] or [[tables]]
    const auto skip = [](Reader& r) { r.skip_rest(); };
    if (const toml::node* n = root.get(t); n != nullptr && n->is_array()) {
      reader.array_of_tables(t, skip);
    } else {
      reader.table(t, skip);
    }
  }
  reader.finish();
  return w;
}

WorldParams parse_world_params(std::string_view toml_text, const std::string& file_name,
                               const std::vector<std::string>& other_tables) {
  return read_world_params(parse_toml(toml_text, file_name), file_name, other_tables);
}

std::string read_config_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), 0, "", "cannot read the configuration file (does it exist?)");
  std::ostringstream buf;
  buf << in.rdbuf();
  return buf.str();
}

WorldParams load_world_params(const std::filesystem::path& path, const std::vector<std::string>& other_tables) {
  return parse_world_params(read_config_file(path), path.string(), other_tables);
}

}  // namespace canhil::physics
