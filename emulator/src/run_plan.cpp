#include "canhil/emulator/run_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/emulator/laptop_link.hpp"

namespace canhil::emulator {
namespace {

// The laptop sides as the run opens them: the first team's [laptop] (and
// every team's own) resolved in place, so that whoever reads the scenario
// later sees what the run uses; per team its side, the second team's
// replicator on only when it has more than one robot and nobody said.
std::vector<LaptopSide> resolve_laptops(Scenario& s, bool realtime) {
  const std::size_t n = s.robot_count();
  for (Team& team : s.teams) {
    if (team.laptop) team.laptop = resolve_laptop(*team.laptop, team.robots, realtime);
  }
  const bool replicate_given = s.laptop.replicate.has_value();
  s.laptop = resolve_laptop(s.laptop, s.teams.size() == 1 ? n : s.teams[0].robots, realtime);
  std::vector<LaptopSide> sides;
  for (std::size_t t = 0; t < s.teams.size(); ++t) {
    const Team& team = s.teams[t];
    LaptopSide side = s.laptop_of(t);
    if (!team.laptop && t > 0 && !replicate_given) side.replicate = team.robots > 1;
    sides.push_back(std::move(side));
  }
  return sides;
}

// The longest `field` the run's external sides give.
// The longest `field` of the teams' external sides (`s` complete: one team at least).
double longest(const Scenario& s, double ExternalSide::*field) {
  double most = 0;
  for (std::size_t t = 0; t < s.teams.size(); ++t) most = std::max(most, s.external_of(t).*field);
  return most;
}

ExternalPlan resolve_external(const Scenario& s) {
  ExternalPlan e;
  e.conductor.answer_limit = from_seconds(longest(s, &ExternalSide::answer_limit_s));
  e.conductor.busy_limit = from_seconds(longest(s, &ExternalSide::busy_limit_s));
  e.conductor.spin = from_seconds(longest(s, &ExternalSide::spin_us) * 1e-6);
  e.attach_limit_s = longest(s, &ExternalSide::attach_limit_s);
  e.bus_spin_us = longest(s, &ExternalSide::bus_spin_us);
  e.syslog = s.external.syslog;
  for (std::size_t r = 0; r < s.robot_count(); ++r) {
    const std::size_t team = s.team_of(r);
    const ExternalSide& side = s.external_of(team);
    for (const std::string& c : side.processes)
      e.launches.push_back({r, team, s.agents[r], expand_command(c, s, r), side.syslog});
  }
  return e;
}

}  // namespace

std::string expand_command(std::string command, const Scenario& scenario, std::size_t robot) {
  const auto replace = [&command](const std::string& key, const std::string& value) {
    for (std::size_t at = command.find(key); at != std::string::npos; at = command.find(key, at + value.size())) {
      command.replace(at, key.size(), value);
    }
  };
  const auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v + 0.0);  // + 0.0: -0 prints as 0
    return std::string(text);
  };
  const physics::Placement& at = scenario.world.robots.at(robot);
  const double goal_x = scenario.world.field.length_m / 2;
  replace("{agent}", std::to_string(scenario.agents.at(robot)));
  replace("{iface}", scenario.interfaces.at(robot));
  replace("{x}", number(at.x_m));
  replace("{y}", number(at.y_m));
  replace("{heading}", number(at.heading_deg));
  replace("{goal_x}", number(scenario.teams.at(scenario.team_of(robot)).attacks_positive_x ? goal_x : -goal_x));
  return command;
}

Scenario half_scenario(const Scenario& scenario, int half) {
  Scenario s = scenario;
  if (half % 2 == 0) return s;
  for (physics::Placement& p : s.world.robots) {
    p.x_m = -p.x_m;
    p.y_m = -p.y_m;
    p.heading_deg = std::remainder(p.heading_deg + 180.0, 360.0);
  }
  for (Team& t : s.teams) t.attacks_positive_x = !t.attacks_positive_x;
  auto& states = s.coach.team_game_states;
  if (states.size() == 2) std::swap(states[0], states[1]);
  s.source_toml.clear();  // no longer the file's text
  return s;
}

Scenario overridden(Scenario s, const RunOverrides& o) {
  if (o.half) s = half_scenario(s, *o.half);
  LaptopSide& side = s.laptop;
  if (o.rtdb_lib) side.rtdb_lib = *o.rtdb_lib;
  if (o.rtdb_items) side.rtdb_items = *o.rtdb_items;
  if (o.rtdb_ini) side.rtdb_ini = *o.rtdb_ini;
  if (o.layout) side.layout = *o.layout;
  if (o.pman) side.pman = *o.pman;
  if (o.kick_power) s.kick_power = *o.kick_power;
  if (const auto b = o.bit_rate; b && (!(*b == 0 || (*b >= 10'000 && *b <= 1'000'000)) || *b != std::floor(*b))) {
    throw OverrideError("--bit-rate takes 10000..1000000 bit/s, or 0 for an instant bus (no wire time, no errors)");
  }
  if (o.seed) s.seed = *o.seed;
  if (!o.processes.empty()) s.external.processes = o.processes;
  if (o.answer_limit_s) {
    if (!(*o.answer_limit_s >= 0.01 && *o.answer_limit_s <= 3600)) {
      throw OverrideError("--answer-limit takes 0.01..3600 s");
    }
    s.external.answer_limit_s = *o.answer_limit_s;
    for (Team& team : s.teams) {
      if (team.external) team.external->answer_limit_s = *o.answer_limit_s;  // the flag is the whole run's
    }
  }
  for (const std::string& f : o.faults) {
    try {
      s.faults.push_back(can_nodes::parse_fault(f));
    } catch (const SetupError& e) {
      throw OverrideError(std::string("--fault: ") + e.what());
    }
  }
  if (o.robots) {
    if (s.world.robots.empty()) s.world.robots.push_back(kDefaultPlacement);  // the file's first robot, or the default
    s.world.robots.resize(*o.robots, kDefaultPlacement);
    if (!s.emulate.empty()) s.emulate.resize(*o.robots, can_nodes::NodeSet::all());
  }
  if (!o.interfaces.empty()) s.interfaces = o.interfaces;
  if (!o.agents.empty()) s.agents = o.agents;
  if (!o.emulate.empty()) s.emulate = o.emulate;
  return s;
}

namespace {

// The buses' physics: --bit-rate over [bus] over the DBC's Baudrate (a
// message set without one: an instant bus). The Baudrate alone times only a
// run whose buses are all canhil's (virtual time, in process): a run on the
// wall clock or with the team's processes is on the machine's SocketCAN,
// whose kernel vcan cannot carry a wire while canhil's user-space bus can,
// and one command must give one run on every machine (a match's --jobs 1 on
// vcan and --jobs 2 on user-space buses the same records).
void resolve_bus(const BusSettings& file, std::optional<double> flag, SessionOptions& options) {
  BusPhysics& bus = options.bus;
  if (flag) {
    bus.bit_rate = static_cast<std::uint32_t>(*flag);  // overridden() checked it
    bus.from = BusPhysics::From::kFlag;
  } else if (file.bit_rate) {
    bus.bit_rate = *file.bit_rate;
    bus.from = BusPhysics::From::kScenario;
  } else if (options.realtime || options.external) {
    bus.bit_rate = 0;
    bus.from = BusPhysics::From::kSocketCan;
  } else if (const auto baud = options.messages->codec().database().baudrate()) {
    bus.bit_rate = *baud;
    bus.from = BusPhysics::From::kDbc;
  } else {
    bus.bit_rate = 0;
    bus.from = BusPhysics::From::kNoBaudrate;
  }
  bus.data_bit_rate = file.data_bit_rate.value_or(0);
  if (file.restart_ms) {
    bus.restart = *file.restart_ms > 0 ? std::optional<Nanos>(from_ms(*file.restart_ms)) : std::nullopt;
  }
  bus.tx_queue = file.tx_queue.value_or(bus.tx_queue);
  if (bus.timed()) {
    options.ftt.bit_rate = bus.bit_rate;  // the schedule's wire times at the wire's rate
    // A timed wire stamps frames at their end of frame: canhil's in virtual
    // time and on the user-space bus, and a real adapter's controller.
    options.ftt.stamps = frames::StampAt::kEndOfFrame;
  }
}

}  // namespace

std::string describe_bus(const BusPhysics& bus) {
  char line[256];
  if (bus.timed()) {
    std::snprintf(line, sizeof line, "each robot's bus on a timed wire at %g kbit/s (%s; --bit-rate 0: instant)",
                  bus.bit_rate / 1e3, bus.source());
  } else {
    const bool zero = bus.from == BusPhysics::From::kFlag || bus.from == BusPhysics::From::kScenario;
    const std::string why = std::string(bus.source()) + (zero ? " 0" : "");
    std::snprintf(line, sizeof line,
                  "instant buses (%s): every frame at once, no wire time, arbitration or errors (--bit-rate B: a "
                  "timed wire)",
                  why.c_str());
  }
  return line;
}

RunPlan plan_run(Scenario scenario, SessionOptions options, const RunOverrides& o) {
  if (!options.messages) throw SetupError("a run needs a message set");
  scenario = overridden(std::move(scenario), o);
  RunPlan plan;
  try {
    plan.length = scenario.run_length(o.duration_s, options.realtime);
  } catch (const SetupError& e) {
    throw OverrideError(e.what());
  }
  complete(scenario);
  if (options.vision_on) plan.laptops = resolve_laptops(scenario, options.realtime || options.external);
  // The scenario's camera imperfections over the options' (exact geometry by default).
  vision_emu::VisionParams& vision = options.vision;
  const VisionImperfections& imperfect = scenario.vision;
  vision.point_noise_m = imperfect.point_noise_m.value_or(vision.point_noise_m);
  vision.ball_noise_m = imperfect.ball_noise_m.value_or(vision.ball_noise_m);
  vision.detection_probability = imperfect.detection_probability.value_or(vision.detection_probability);
  vision.latency_s = imperfect.latency_s.value_or(vision.latency_s);
  resolve_bus(scenario.bus, o.bit_rate, options);
  if (options.external) plan.external = resolve_external(scenario);
  plan.scenario = std::move(scenario);
  plan.options = std::move(options);
  return plan;
}

RunPlan plan_run(const std::optional<std::filesystem::path>& file, const RunOverrides& o, SessionOptions options) {
  const std::filesystem::path path = file ? *file : shipped_scenario("one_robot.toml");
  Scenario s = read_scenario(path);
  options.realtime = o.mode == RunMode::kRealtime;
  options.external = o.mode == RunMode::kExternal;
  RunPlan plan;
  try {
    plan = plan_run(std::move(s), std::move(options), o);
  } catch (const OverrideError&) {
    throw;
  } catch (const SetupError& e) {  // what the file (or an override) leaves wrong or incomplete
    throw SetupError((file ? file->string() + ": " : std::string()) + e.what());
  }
  plan.source = file.value_or(std::filesystem::path());
  return plan;
}

}  // namespace canhil::emulator
