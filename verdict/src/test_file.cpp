// A test file read and checked (test_file.hpp).
#include "canhil/verdict/test_file.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/coach.hpp"
#include "canhil/emulator/table_reader.hpp"
#include "canhil/physics/config.hpp"
#include "canhil/physics/config_toml.hpp"

namespace canhil::verdict {
namespace {

using emulator::TableReader;

constexpr double kLongest_s = 24 * 3600.0;  // a day of virtual time

constexpr std::array<Check, 10> kChecks = {
    Check::kBallInGoal, Check::kRobotNear,      Check::kSpeedBelow,   Check::kFttViolations, Check::kErrorFrames,
    Check::kJitter,     Check::kHandlerLatency, Check::kWithinBounds, Check::kRtdb,          Check::kProcesses};

// The fields each check takes, beside name and robot.
std::vector<std::string> fields_of(Check c) {
  switch (c) {
    case Check::kBallInGoal:
      return {"by_s"};
    case Check::kRobotNear:
      return {"within_m", "by_s", "from_s"};
    case Check::kSpeedBelow:
      return {"after", "after_s", "within_ms", "hold_ms"};
    case Check::kFttViolations:
      return {"message"};
    case Check::kErrorFrames:
    case Check::kHandlerLatency:
    case Check::kWithinBounds:
      return {};
    case Check::kJitter:
      return {"message"};
    case Check::kRtdb:
      return {"between", "at_s", "from_s", "age_at_most_ms"};
    case Check::kProcesses:
      return {"exit_codes"};
  }
  return {};
}

std::string check_list() {
  std::string list;
  for (Check c : kChecks) list += std::string(list.empty() ? "" : ", ") + check_key(c);
  return list;
}

// A list of `n` to `m` numbers.
std::vector<double> numbers(const TableReader& r, const std::string& key, std::size_t n, std::size_t m,
                            const char* example) {
  std::vector<double> out;
  const toml::array* a = r.array(key);
  if (a == nullptr) return out;
  for (const toml::node& e : *a) {
    const auto v = e.value<double>();
    if (!v || !std::isfinite(*v)) r.fail(e, key, std::string("must be numbers, e.g. ") + key + " = " + example);
    out.push_back(*v);
  }
  if (out.size() < n || out.size() > m) r.fail(*r.get(key), key, std::string("give ") + example);
  return out;
}

// A whole number from lo to hi, or nothing when the field is not there.
std::optional<double> whole(const TableReader& r, const std::string& key, double lo, double hi) {
  const auto v = r.number(key, lo, hi);
  if (v && *v != std::floor(*v)) r.fail(*r.get(key), key, "must be a whole number");
  return v;
}

std::size_t robot_of(const TableReader& r) { return static_cast<std::size_t>(whole(r, "robot", 0, 11).value_or(0)); }

Event read_event(const toml::table& t, std::size_t index, const std::string& file) {
  const TableReader r(t, "events", file, {"name", "at_s", "fault", "coach", "robot", "running", "ball", "set_pose"});
  Event e;
  e.line = static_cast<int>(t.source().begin.line);
  e.name = r.text("name", "\"laptop silent\"").value_or("event " + std::to_string(index + 1));
  const auto at = r.number("at_s", 0, kLongest_s);
  if (!at) r.fail(t, "at_s", "missing: when the event happens, in seconds of the run, e.g. at_s = 2.5");
  e.at_s = *at;
  const char* kinds[] = {"fault", "coach", "ball", "set_pose"};
  int given = 0;
  for (const char* k : kinds) given += r.get(k) != nullptr ? 1 : 0;
  if (given != 1) {
    r.fail(t, "fault",
           "give exactly one of fault = \"RULE\", coach = \"STATE\", ball = [x, y] or set_pose = [x, y, "
           "heading_rad]");
  }
  if (const auto f = r.text("fault", "\"silence:laptop:2\"")) {
    e.kind = Event::Kind::kFault;
    try {
      e.fault = can_nodes::parse_fault(*f);
    } catch (const SetupError& err) {
      r.fail(*r.get("fault"), "fault", err.what());
    }
  } else if (r.get("coach") != nullptr) {
    e.kind = Event::Kind::kCoach;
    const std::string state = *r.text("coach", "\"stop\"");
    if (!emulator::is_game_state(state)) {
      std::string known;
      for (const auto s : emulator::kGameStates) known += std::string(known.empty() ? "" : ", ") + std::string(s);
      r.fail(*r.get("coach"), "coach", "not a game state; the states are " + known);
    }
    e.game_state = state;
    e.running = r.boolean("running");
    e.robot = robot_of(r);
    if (r.get("robot") != nullptr && !e.running) {
      r.fail(*r.get("robot"), "robot",
             "a coach order for one robot says whether it plays: add running = false (or true); without robot, "
             "coach = \"" +
                 state + "\" is every team's game state");
    }
    if (e.running) e.game_state.reset();  // one robot's: played or not
  } else if (r.get("ball") != nullptr) {
    e.kind = Event::Kind::kBall;
    const auto b = numbers(r, "ball", 2, 4, "[x_m, y_m] or [x_m, y_m, vx_m_s, vy_m_s]");
    std::copy(b.begin(), b.end(), e.ball);
  } else {
    e.kind = Event::Kind::kSetPose;
    const auto p = numbers(r, "set_pose", 3, 3, "[x_m, y_m, heading_rad]");
    e.pose = {p[0], p[1], p[2]};
    e.robot = robot_of(r);
  }
  if (e.kind != Event::Kind::kCoach && e.kind != Event::Kind::kSetPose && r.get("robot") != nullptr) {
    r.fail(*r.get("robot"), "robot", "only a coach order for one robot, or a set-pose, names a robot");
  }
  if (e.kind != Event::Kind::kCoach && r.get("running") != nullptr) {
    r.fail(*r.get("running"), "running", "only a coach order for one robot says whether it plays");
  }
  return e;
}

Expectation read_expectation(const toml::table& t, std::size_t index, const std::string& file) {
  // Which check: exactly one key of kChecks.
  std::optional<Check> check;
  for (Check c : kChecks) {
    if (t.get(check_key(c)) == nullptr) continue;
    if (check) {
      throw physics::ConfigError(file, static_cast<int>(t.get(check_key(c))->source().begin.line),
                                 std::string("expect.") + check_key(c),
                                 std::string("an expectation checks one thing: this one already has ") +
                                     check_key(*check) + "; give another [[expect]]");
    }
    check = c;
  }
  if (!check) {
    throw physics::ConfigError(file, static_cast<int>(t.source().begin.line), "expect",
                               "says nothing to check; give one of " + check_list());
  }
  std::vector<std::string> known = {"name", "robot", check_key(*check)};
  for (const std::string& f : fields_of(*check)) known.push_back(f);
  const TableReader r(t, "expect", file, known);
  Expectation x;
  x.check = *check;
  x.line = static_cast<int>(t.source().begin.line);
  x.name = r.text("name", "\"the robot brakes\"")
               .value_or(std::string(check_key(*check)) + " (expectation " + std::to_string(index + 1) + ")");
  x.robot = robot_of(r);
  x.by_s = r.number("by_s", 0, kLongest_s);
  x.from_s = r.number("from_s", 0, kLongest_s).value_or(0);
  const std::string key = check_key(*check);
  switch (*check) {
    case Check::kBallInGoal: {
      x.goal = *r.text(key, "\"opponent\"");
      if (x.goal != "opponent" && x.goal != "own" && x.goal != "+x" && x.goal != "-x" && x.goal != "any") {
        r.fail(*r.get(key), key, "must be \"opponent\", \"own\", \"+x\", \"-x\" or \"any\"");
      }
      break;
    }
    case Check::kRobotNear: {
      const toml::node& n = *r.get(key);
      if (n.value<std::string>() == std::optional<std::string>("ball")) {
        x.near_ball = true;
      } else {
        const auto p = numbers(r, key, 2, 2, "\"ball\" or [x_m, y_m]");
        if (p.empty()) r.fail(n, key, "must be \"ball\" or [x_m, y_m]");
        x.point[0] = p[0];
        x.point[1] = p[1];
      }
      x.within_m = r.number("within_m", 0, 50).value_or(x.within_m);
      if (x.by_s && *x.by_s < x.from_s) r.fail(*r.get("by_s"), "by_s", "comes before from_s");
      break;
    }
    case Check::kSpeedBelow:
      x.speed_m_s = *r.number(key, 0, 20);
      x.after = r.text("after", "\"laptop silent\"").value_or("");
      x.after_s = r.number("after_s", 0, kLongest_s);
      if (x.after.empty() == !x.after_s) {
        r.fail(t, "after", "give after = \"EVENT\" (an event's name) or after_s = SECONDS, one of them");
      }
      x.within_ms = r.number("within_ms", 0, 1e6).value_or(x.within_ms);
      x.hold_ms = r.number("hold_ms", 0, 1e6).value_or(x.hold_ms);
      break;
    case Check::kFttViolations:
    case Check::kErrorFrames:
      x.at_most = static_cast<std::uint64_t>(*whole(r, key, 0, 1e12));
      x.message = r.text("message", "\"M6_1\"").value_or("");
      break;
    case Check::kJitter:
      x.bound_ms = *r.number(key, 0, 1e6);
      x.message = r.text("message", "\"M6_1\"").value_or("");
      if (x.message.empty()) r.fail(t, "message", "missing: whose jitter, e.g. message = \"M1\"");
      break;
    case Check::kHandlerLatency:
      x.bound_ms = *r.number(key, 0, 1e6);
      break;
    case Check::kWithinBounds:
    case Check::kProcesses:
      if (!*r.boolean(key)) r.fail(*r.get(key), key, "can only be true (leave the expectation out otherwise)");
      for (const double c : numbers(r, "exit_codes", 1, 256, "[0, 130]")) {
        if (c != std::floor(c) || c < 0 || c > 255)
          r.fail(*r.get("exit_codes"), "exit_codes", "exit statuses are 0 to 255");
        x.exit_codes.push_back(static_cast<int>(c));
      }
      break;
    case Check::kRtdb: {
      const std::string what = *r.text(key, "\"CMD_POS.x\"");
      const auto dot = what.find('.');
      if (dot == std::string::npos || dot == 0 || dot + 1 == what.size()) {
        r.fail(*r.get(key), key, "must be ITEM.quantity, e.g. \"CMD_POS.x\" (`canhil rtdb list` names them)");
      }
      x.item = what.substr(0, dot);
      x.quantity = what.substr(dot + 1);
      const auto b = numbers(r, "between", 2, 2, "[low, high]");
      if (b.empty()) r.fail(t, "between", "missing: the bounds, in the quantity's SI unit, e.g. between = [1.4, 1.6]");
      if (b[0] > b[1]) r.fail(*r.get("between"), "between", "the low bound comes first");
      x.low = b[0];
      x.high = b[1];
      x.at_s = r.number("at_s", 0, kLongest_s);
      if (x.at_s && r.get("from_s") != nullptr) {
        r.fail(*r.get("from_s"), "from_s", "give at_s (at one instant) or from_s (from then to the end), not both");
      }
      x.age_ms = r.number("age_at_most_ms", 0, 1e9);
      break;
    }
  }
  return x;
}

}  // namespace

const char* check_key(Check c) noexcept {
  switch (c) {
    case Check::kBallInGoal:
      return "ball_in_goal";
    case Check::kRobotNear:
      return "robot_near";
    case Check::kSpeedBelow:
      return "speed_below_m_s";
    case Check::kFttViolations:
      return "ftt_violations_at_most";
    case Check::kErrorFrames:
      return "error_frames_at_most";
    case Check::kJitter:
      return "jitter_p99_at_most_ms";
    case Check::kHandlerLatency:
      return "handler_latency_p99_at_most_ms";
    case Check::kWithinBounds:
      return "within_bounds";
    case Check::kRtdb:
      return "rtdb";
    case Check::kProcesses:
      return "processes_ok";
  }
  return "?";
}

const Event* TestFile::event(const std::string& called) const {
  for (const Event& e : events) {
    if (e.name == called) return &e;
  }
  return nullptr;
}

TestFile parse_test_file(const std::string& text, const std::filesystem::path& file_name) {
  const std::string file = file_name.string();
  const toml::table root = physics::parse_toml(text, file);
  if (root.get("test") == nullptr) {
    for (const char* scenario_table : {"run", "robots", "teams", "ball_start", "field", "external", "laptop"}) {
      if (root.get(scenario_table) == nullptr) continue;
      throw physics::ConfigError(file, static_cast<int>(root.get(scenario_table)->source().begin.line), scenario_table,
                                 "this is a scenario, not a test file: give canhil test the test files, whose [test] "
                                 "table names their scenario (keep scenarios apart, e.g. in tests/scenarios/)");
    }
  }
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    if (key != "test" && key != "events" && key != "expect") {
      throw physics::ConfigError(file, static_cast<int>(v.source().begin.line), key,
                                 "unknown table; a test file has [test], [[events]] and [[expect]]");
    }
  }
  TestFile f;
  f.path = file_name;
  const toml::table* test = root["test"].as_table();
  if (test == nullptr) {
    throw physics::ConfigError(file, 1, "test",
                               "missing: a test file starts with [test] and its scenario, e.g. scenario = "
                               "\"one_robot.toml\"");
  }
  const TableReader r(*test, "test", file,
                      {"name", "scenario", "duration_s", "seed", "bit_rate", "faults", "external"});
  f.name = r.text("name", "\"the robot scores\"").value_or(file_name.stem().string());
  const auto scenario = r.text("scenario", "\"../one_robot.toml\"");
  if (!scenario) r.fail(*test, "scenario", "missing: the scenario the test runs, relative to this file");
  f.scenario = file_name.parent_path() / *scenario;
  f.duration_s = r.number("duration_s", 0.01, kLongest_s);
  if (const auto s = whole(r, "seed", 0, 9.0e15)) f.seed = static_cast<std::uint64_t>(*s);
  f.bit_rate = whole(r, "bit_rate", 0, 1'000'000);
  if (f.bit_rate && *f.bit_rate != 0 && *f.bit_rate < 10'000) {
    r.fail(*r.get("bit_rate"), "bit_rate", "must be 0 (the instant bus) or from 10000 to 1000000 bit/s");
  }
  f.external = r.boolean("external").value_or(false);
  if (const toml::array* faults = r.array("faults")) {
    for (const toml::node& n : *faults) {
      const auto rule = n.value<std::string>();
      if (!rule) r.fail(n, "faults", "must be texts, e.g. faults = [\"drop:M4_1:0.1\"]");
      try {
        can_nodes::parse_fault(*rule);
      } catch (const SetupError& err) {
        r.fail(n, "faults", err.what());
      }
      f.faults.push_back(*rule);
    }
  }
  if (const toml::node* events = root.get("events")) {
    const toml::array* list = events->as_array();
    if (list == nullptr) throw physics::ConfigError(file, 1, "events", "must be [[events]] tables");
    for (const toml::node& n : *list) {
      if (!n.is_table()) throw physics::ConfigError(file, 1, "events", "must be [[events]] tables");
      Event e = read_event(*n.as_table(), f.events.size(), file);
      if (f.event(e.name) != nullptr) {
        throw physics::ConfigError(file, e.line, "events.name", "'" + e.name + "' names two events");
      }
      f.events.push_back(std::move(e));
    }
  }
  std::stable_sort(f.events.begin(), f.events.end(), [](const Event& a, const Event& b) { return a.at_s < b.at_s; });
  const toml::array* expect = root["expect"].as_array();
  if (expect == nullptr || expect->empty()) {
    throw physics::ConfigError(file, 1, "expect", "missing: a test expects something; give [[expect]] tables");
  }
  for (const toml::node& n : *expect) {
    if (!n.is_table()) throw physics::ConfigError(file, 1, "expect", "must be [[expect]] tables");
    Expectation x = read_expectation(*n.as_table(), f.expectations.size(), file);
    if (x.check == Check::kSpeedBelow && !x.after.empty() && f.event(x.after) == nullptr) {
      std::string names;
      for (const Event& e : f.events) names += std::string(names.empty() ? "" : ", ") + "'" + e.name + "'";
      throw physics::ConfigError(
          file, x.line, "expect.after",
          "no event is named '" + x.after + "'; the events are " + (names.empty() ? std::string("none") : names));
    }
    for (const Expectation& other : f.expectations) {
      if (other.name == x.name) {
        throw physics::ConfigError(file, x.line, "expect.name", "'" + x.name + "' names two expectations");
      }
    }
    f.expectations.push_back(std::move(x));
  }
  return f;
}

TestFile load_test_file(const std::filesystem::path& path) {
  return parse_test_file(physics::read_config_file(path), path);
}

}  // namespace canhil::verdict
