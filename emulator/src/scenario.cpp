#include "canhil/emulator/scenario.hpp"

#include <toml++/toml.h>
#include <algorithm>
#include <cstdio>

#include "canhil/base/assets.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/physics/config.hpp"
#include "canhil/physics/config_toml.hpp"
#include "table_reader.hpp"

namespace canhil::emulator {
namespace {

using detail::TableReader;

void read_run(const TableReader& r, Scenario& s, std::size_t robots) {
  if (const toml::node* n = r.get("duration_s")) {
    const auto v = n->value<double>();
    if (!v || !(*v > 0)) r.fail(*n, "duration_s", "must be a number of seconds above 0");
    s.duration_s = *v;
    s.duration_given = true;
  }
  if (const toml::node* n = r.get("seed")) {
    const auto v = n->value<std::int64_t>();
    if (!v || *v < 0 || !n->is_integer()) r.fail(*n, "seed", "must be a whole number, 0 or more");
    s.seed = static_cast<std::uint64_t>(*v);
  }
  if (const toml::node* n = r.get("kick_power")) {
    const auto v = n->value<std::int64_t>();
    if (!v || !n->is_integer() || *v < 0 || *v > s.world.robot.kicker.max_power) {
      r.fail(*n, "kick_power", "must be a whole number from 0 to robot.kicker.max_power");
    }
    s.kick_power = static_cast<int>(*v);
  }
  if (const toml::array* a = r.array("interfaces")) {
    for (const toml::node& e : *a) {
      const auto v = e.value<std::string>();
      if (!v || v->empty() || v->size() > 15) r.fail(e, "interfaces", "must be interface names such as \"vcan0\"");
      s.interfaces.push_back(*v);
    }
    if (s.interfaces.size() != robots) {
      r.fail(*r.get("interfaces"), "interfaces",
             "give one interface per robot: the file places " + std::to_string(robots) + " robot(s)");
    }
  }
  if (const toml::array* a = r.array("agents")) {
    for (const toml::node& e : *a) {
      const auto v = e.value<std::int64_t>();
      if (!v || !e.is_integer() || *v < kFirstAgent || *v > kLastAgent) {
        r.fail(e, "agents", "agent numbers are whole numbers 1..6");
      }
      if (std::count(s.agents.begin(), s.agents.end(), *v) != 0) {
        r.fail(e, "agents", "agent " + std::to_string(*v) + " appears twice; give each robot its own");
      }
      s.agents.push_back(static_cast<int>(*v));
    }
    if (s.agents.size() != robots) {
      r.fail(*r.get("agents"), "agents",
             "give one agent number per robot: the file places " + std::to_string(robots) + " robot(s)");
    }
  }
  if (const toml::array* a = r.array("faults")) {
    for (const toml::node& e : *a) {
      const auto v = e.value<std::string>();
      if (!v) r.fail(e, "faults", "must be a list of fault texts such as \"drop:M4_1:0.1\"");
      try {
        s.faults.push_back(can_nodes::parse_fault(*v));
      } catch (const SetupError& err) {
        r.fail(e, "faults", err.what());
      }
    }
  }
}

// [run] emulate: one list of node names for every robot (those that do not
// give their own in [[teams.robots]]), or, without teams, one list per robot.
void read_emulate(const TableReader& r, Scenario& s, std::size_t robots, bool teams) {
  s.emulate.resize(robots);  // an empty set: not given yet
  const toml::array* a = r.array("emulate");
  if (a != nullptr && !a->empty() && a->front().is_array()) {
    if (teams) r.fail(*a, "emulate", "with [[teams]], give a robot's own list in its [[teams.robots]]");
    if (a->size() != robots) {
      r.fail(*a, "emulate",
             "give one list per robot (the file places " + std::to_string(robots) + "), or one list for all of them");
    }
    for (std::size_t k = 0; k < robots; ++k) s.emulate[k] = r.node_set((*a)[k], "emulate");
    return;
  }
  const can_nodes::NodeSet all = a != nullptr ? r.node_set(*a, "emulate") : can_nodes::NodeSet::all();
  for (can_nodes::NodeSet& e : s.emulate) {
    if (e.empty()) e = all;
  }
}

void read_coach(const TableReader& r, Scenario& s, std::size_t robots) {
  if (const auto state = r.text("game_state", "\"start\"")) {
    if (!is_game_state(*state)) {
      std::string list;
      for (const auto g : kGameStates) list += (list.empty() ? "" : ", ") + std::string(g);
      r.fail(*r.get("game_state"), "game_state", "\"" + *state + "\" is not a game state; use one of " + list);
    }
    s.coach.game_state = *state;
  }
  s.coach.players.resize(robots);
  const auto running = r.per_robot<bool>("running", robots, "true or false");
  const auto roles = r.per_robot<std::string>("roles", robots, "role names such as \"striker\"");
  const auto role_auto = r.per_robot<bool>("role_auto", robots, "true or false");
  for (std::size_t k = 0; k < robots; ++k) {
    if (!running.empty()) s.coach.players[k].running = running[k];
    if (!roles.empty()) s.coach.players[k].role = roles[k];
    if (!role_auto.empty()) s.coach.players[k].role_auto = role_auto[k];
  }
}

}  // namespace

namespace detail {

// A path in the file, relative to the file's folder.
std::string beside(const std::string& file, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || file.empty()) return path;
  return (std::filesystem::path(file).parent_path() / p).lexically_normal().string();
}

}  // namespace detail

namespace detail {

void read_laptop(const TableReader& r, LaptopSide& l) {
  if (const auto v = r.text("rtdb_lib", "\"builtin\" or \"/path/to/librtdb.so\"")) {
    l.rtdb_lib = *v == "builtin" ? *v : beside(r.file(), *v);
  }
  if (const auto v = r.text("rtdb_items", "\"../cambada/src/libs/rtdb/rtdb_user.h\"")) {
    l.rtdb_items = beside(r.file(), *v);
  }
  if (const auto v = r.text("rtdb_ini", "\"../cambada/config/rtdb.ini\"")) l.rtdb_ini = beside(r.file(), *v);
  if (const auto v = r.text("layout", "\"cambada\", \"canhil\" or a layout file")) {
    l.layout = (*v == "cambada" || *v == "canhil") ? *v : beside(r.file(), *v);
  }
  if (const auto v = r.text("pman", "\"builtin\", \"none\" or \"/path/to/libpman.so\"")) {
    l.pman = (*v == "builtin" || *v == "none") ? *v : beside(r.file(), *v);
  }
  if (const auto v = r.number("coach_period_s", 0.001, 10.0)) l.coach_period_s = *v;
  if (const auto v = r.number("relocation_delay_s", 0.0, 10.0)) l.relocation_delay_s = *v;
  if (const auto v = r.boolean("replicate")) l.replicate = *v;
  if (const auto v = r.number("replicate_period_s", 0.001, 10.0)) l.replicate_period_s = *v;
  if (const toml::array* a = r.array("pman_processes")) {
    l.pman_processes.clear();
    for (const toml::node& e : *a) {
      const auto v = e.value<std::string>();
      if (!v || v->empty() || v->size() > 30) {
        r.fail(e, "pman_processes", "must be process names such as \"agent\" (the agent number is appended)");
      }
      l.pman_processes.push_back(*v);
    }
  }
}

void read_external(const TableReader& r, ExternalSide& e) {
  if (const toml::array* a = r.array("processes")) {
    for (const toml::node& n : *a) {
      const auto v = n.value<std::string>();
      if (!v || v->find_first_not_of(" \t") == std::string::npos) {
        r.fail(n, "processes",
               "must be command lines such as \"canhil-hwcomm --iface {iface}\" ({agent}, {iface}, {x}, {y}, "
               "{heading} and {goal_x} are the robot's)");
      }
      e.processes.push_back(*v);
    }
  }
  if (const auto v = r.number("answer_limit_s", 0.01, 3600.0)) e.answer_limit_s = *v;
  if (const auto v = r.number("attach_limit_s", 0.1, 3600.0)) e.attach_limit_s = *v;
  if (const auto v = r.number("busy_limit_s", 0.1, 3600.0)) e.busy_limit_s = *v;
  if (const auto v = r.number("spin_us", 0.0, 100000.0)) e.spin_us = *v;
  if (const auto v = r.number("bus_spin_us", 0.0, 100000.0)) e.bus_spin_us = *v;
  if (const auto v = r.text("syslog", "\"log\" (to each process's own log) or \"system\" (the machine's syslog)")) {
    if (*v != "log" && *v != "system") {
      r.fail(*r.get("syslog"), "syslog",
             "must be \"log\" (each process's messages to its own log) or \"system\" (to the machine's syslog)");
    }
    e.syslog = *v;
  }
}

const std::vector<std::string>& laptop_fields() {
  static const std::vector<std::string> fields = {
      "rtdb_lib",       "rtdb_items",     "rtdb_ini",           "layout",    "pman",
      "pman_processes", "coach_period_s", "relocation_delay_s", "replicate", "replicate_period_s"};
  return fields;
}
const std::vector<std::string>& external_fields() {
  static const std::vector<std::string> fields = {"processes", "answer_limit_s", "attach_limit_s", "busy_limit_s",
                                                  "spin_us",   "bus_spin_us",    "syslog"};
  return fields;
}

}  // namespace detail

bool is_game_state(std::string_view name) noexcept {
  return std::find(kGameStates.begin(), kGameStates.end(), name) != kGameStates.end();
}

namespace {

// The file's values, not yet complete.
Scenario read_text(std::string_view toml_text, const std::string& file_name) {
  Scenario s;
  const toml::table root = physics::parse_toml(toml_text, file_name);  // parsed once, for the world and the run
  s.world = physics::read_world_params(
      root, file_name, {"run", "coach", "laptop", "external", "teams", "referee", "vision", "bus", "firmware"});
  const bool teams = detail::read_teams(root, file_name, s);  // places the teams' robots
  if (s.world.robots.empty()) s.world.robots.push_back(kDefaultPlacement);
  const std::size_t robots = s.world.robots.size();
  if (const toml::table* run = root["run"].as_table()) {
    std::vector<std::string> fields = {"duration_s", "seed", "kick_power", "faults", "emulate"};
    if (!teams) fields.insert(fields.end(), {"interfaces", "agents"});  // a team gives its robots'
    const TableReader r(*run, "run", file_name, fields);
    read_run(r, s, robots);
    read_emulate(r, s, robots, teams);
  }
  for (can_nodes::NodeSet& e : s.emulate) {
    if (e.empty()) e = can_nodes::NodeSet::all();  // neither the robot nor [run] says
  }
  if (const toml::table* coach = root["coach"].as_table()) {
    std::vector<std::string> fields = {"game_state"};
    if (!teams) fields.insert(fields.end(), {"running", "roles", "role_auto"});  // a team gives its robots'
    read_coach(TableReader(*coach, "coach", file_name, fields), s, robots);
  }
  if (const toml::table* laptop = root["laptop"].as_table()) {
    detail::read_laptop(TableReader(*laptop, "laptop", file_name, detail::laptop_fields()), s.laptop);
  }
  if (const toml::table* referee = root["referee"].as_table()) {
    const TableReader r(*referee, "referee", file_name,
                        {"enabled", "kickoff_after_goal", "out_of_play", "dropped_ball", "stuck_s", "stuck_radius_m",
                         "restart_pause_s", "touch_distance_m", "restart_distance_m", "in_play_distance_m"});
    RefereeRules& rules = s.referee;
    if (const auto v = r.boolean("enabled")) rules.enabled = *v;
    if (const auto v = r.boolean("kickoff_after_goal")) rules.kickoff_after_goal = *v;
    if (const auto v = r.boolean("out_of_play")) rules.out_of_play = *v;
    if (const auto v = r.boolean("dropped_ball")) rules.dropped_ball = *v;
    if (const auto v = r.number("stuck_s", 0.1, 3600.0)) rules.stuck_s = *v;
    if (const auto v = r.number("stuck_radius_m", 0.0, 20.0)) rules.stuck_radius_m = *v;
    if (const auto v = r.number("restart_pause_s", 0.0, 60.0)) rules.restart_pause_s = *v;
    if (const auto v = r.number("touch_distance_m", 0.0, 2.0)) rules.touch_distance_m = *v;
    if (const auto v = r.number("restart_distance_m", 0.0, 5.0)) rules.restart_distance_m = *v;
    if (const auto v = r.number("in_play_distance_m", 0.0, 5.0)) rules.in_play_distance_m = *v;
  }
  if (const toml::table* vision = root["vision"].as_table()) {
    const TableReader r(*vision, "vision", file_name,
                        {"point_noise_m", "ball_noise_m", "detection_probability", "latency_s"});
    s.vision.point_noise_m = r.number("point_noise_m", 0.0, 1.0);
    s.vision.ball_noise_m = r.number("ball_noise_m", 0.0, 1.0);
    s.vision.detection_probability = r.number("detection_probability", 0.0, 1.0);
    s.vision.latency_s = r.number("latency_s", 0.0, 1.0);
  }
  if (const toml::table* bus = root["bus"].as_table()) {
    const TableReader r(*bus, "bus", file_name, {"bit_rate", "data_bit_rate", "restart_ms", "tx_queue"});
    if (const auto v = r.number("bit_rate", 0, 1'000'000)) s.bus.bit_rate = static_cast<std::uint32_t>(*v);
    if (const auto v = r.number("data_bit_rate", 0, 8'000'000)) s.bus.data_bit_rate = static_cast<std::uint32_t>(*v);
    if (const auto v = r.number("restart_ms", 0, 60'000)) s.bus.restart_ms = *v;
    if (const auto v = r.number("tx_queue", 1, 4096)) s.bus.tx_queue = static_cast<std::size_t>(*v);
  }
  if (const toml::table* firmware = root["firmware"].as_table()) {
    const TableReader r(*firmware, "firmware", file_name, {"watchdog_ms", "motor_watchdog_ms", "alive_timeout_ms"});
    s.firmware.watchdog_ms = r.number("watchdog_ms", 1, 60'000);
    s.firmware.motor_watchdog_ms = r.number("motor_watchdog_ms", 1, 60'000);
    s.firmware.alive_timeout_ms = r.number("alive_timeout_ms", 1, 60'000);
  }
  if (const toml::table* external = root["external"].as_table()) {
    detail::read_external(TableReader(*external, "external", file_name, detail::external_fields()), s.external);
  }
  s.source_toml = std::string(toml_text);
  return s;
}

}  // namespace

Scenario parse_scenario(std::string_view toml_text, const std::string& file_name) {
  Scenario s = read_text(toml_text, file_name);
  complete(s);
  return s;
}

Scenario read_scenario(const std::filesystem::path& path) {
  return read_text(physics::read_config_file(path), path.string());
}

void complete(Scenario& s) {
  if (s.world.robots.empty()) s.world.robots.push_back(kDefaultPlacement);
  const std::size_t robots = s.world.robots.size();
  detail::complete_teams(s);
  constexpr std::size_t kMostRobots = kLastAgent - kFirstAgent + 1;
  if (s.interfaces.empty()) s.interfaces.resize(robots);
  if (s.agents.empty()) s.agents.resize(robots, 0);
  if (s.interfaces.size() != robots || s.agents.size() != robots) {
    throw SetupError("give one interface and one agent number per robot (" + std::to_string(robots) + " robots, " +
                     std::to_string(s.interfaces.size()) + " interfaces, " + std::to_string(s.agents.size()) +
                     " agents)");
  }
  for (std::size_t k = 0; k < robots; ++k) {
    if (s.interfaces[k].empty()) s.interfaces[k] = "vcan" + std::to_string(k);
  }
  for (const Team& team : s.teams) {
    const auto first = s.agents.begin() + static_cast<std::ptrdiff_t>(team.first_robot);
    const auto last = first + static_cast<std::ptrdiff_t>(team.robots);
    if (team.robots > kMostRobots) {
      throw SetupError("a team takes at most " + std::to_string(kMostRobots) + " robots (agents CAMBADA_1..6); " +
                       (s.teams.size() > 1 ? "team " + team.name + " has " : "this run places ") +
                       std::to_string(team.robots));
    }
    for (auto a = first; a != last; ++a) {
      if (*a == 0) *a = kFirstAgent + static_cast<int>(a - first);  // the team's next agent number
    }
    for (auto a = first; a != last; ++a) {
      if (*a < kFirstAgent || *a > kLastAgent) {
        throw SetupError("agent numbers are " + std::to_string(kFirstAgent) + ".." + std::to_string(kLastAgent) +
                         ", got " + std::to_string(*a));
      }
      if (std::count(first, last, *a) > 1) {
        throw SetupError("agent " + std::to_string(*a) + " is given to two robots" +
                         (s.teams.size() > 1 ? " of team " + team.name : std::string()) + "; give each robot its own");
      }
    }
  }
  if (s.emulate.empty()) s.emulate.resize(robots, can_nodes::NodeSet::all());
  if (s.emulate.size() != robots) {
    throw SetupError("give one set of emulated nodes per robot (" + std::to_string(robots) + " robots, " +
                     std::to_string(s.emulate.size()) + " sets), or none for all eight");
  }
  for (std::size_t k = 0; k < robots; ++k) {
    if (s.emulate[k].empty()) {
      throw SetupError("robot " + std::to_string(k + 1) +
                       " emulates no node; leave at least one to canhil (a robot of real boards only needs no "
                       "emulator)");
    }
    if (std::count(s.interfaces.begin(), s.interfaces.end(), s.interfaces[k]) > 1) {
      throw SetupError("interface " + s.interfaces[k] + " is given to two robots; each robot has its own bus");
    }
  }
  if (!is_game_state(s.coach.game_state)) {
    throw SetupError("\"" + s.coach.game_state + "\" is not a game state (emulator/coach.hpp lists them)");
  }
  s.coach.players.resize(robots);
}

Scenario load_scenario(const std::filesystem::path& path) {
  return parse_scenario(physics::read_config_file(path), path.string());
}

std::filesystem::path shipped_scenario(const std::string& name) {
  namespace fs = std::filesystem;
  return installed_or_built({fs::path("../share/canhil/scenarios") / name}, fs::path(CANHIL_SOURCE_SCENARIOS) / name);
}

RunLength Scenario::run_length(std::optional<double> flag, bool realtime) const {
  if (flag) {
    if (realtime && *flag == 0) return {0, "--duration 0"};
    if (!(*flag > 0)) {
      throw SetupError(realtime ? "--duration takes seconds above 0, or 0 for until Ctrl-C"
                                : "--duration takes seconds above 0");
    }
    return {*flag, "--duration"};
  }
  if (duration_given) return {duration_s, "the scenario's duration_s"};
  if (realtime) return {0, "no --duration, no duration_s in the scenario"};
  return {duration_s, "the default: no duration_s in the scenario"};
}

}  // namespace canhil::emulator
