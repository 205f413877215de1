// A test file's run in virtual time: its events at their times, what its
// expectations need recorded as it goes, then every expectation judged
// (verdict.hpp).
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "canhil/base/setup_error.hpp"
#include "canhil/base/text_format.hpp"
#include "canhil/emulator/laptop_link.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/external/external_run.hpp"
#include "canhil/external/team_processes.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/frames/dbc.hpp"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"
#include "canhil/timing/bus_analysis.hpp"
#include "record.hpp"

namespace canhil::verdict {
namespace {

using detail::Record;

// What an event does to the running session.
void apply(const Event& e, emulator::Session& session) {
  switch (e.kind) {
    case Event::Kind::kFault: {
      can_nodes::FaultRule rule = e.fault;  // its own @SECONDS count from the event
      const Nanos at = from_seconds(e.at_s);
      rule.from += at;
      if (rule.until != kNever) rule.until += at;
      session.apply(emulator::InjectFault{rule});
      break;
    }
    case Event::Kind::kCoach: {
      emulator::SetCoach c;
      c.game_state = e.game_state;
      if (e.running) {
        c.robot = e.robot;
        c.running = e.running;
      }
      session.apply(c);
      break;
    }
    case Event::Kind::kBall: {
      const double radius = session.scenario().world.ball.radius_m;
      session.apply(emulator::MoveBall{{e.ball[0], e.ball[1], radius}, {e.ball[2], e.ball[3], 0}});
      break;
    }
    case Event::Kind::kSetPose: {
      const emulator::Rig& rig = session.rig(e.robot);
      emulator::LaptopLink* link = session.laptop(rig.team);
      if (link == nullptr) throw SetupError("a set-pose needs the team's RTDB (the scenario runs without vision)");
      link->place(rig.in_team, e.pose);
      break;
    }
  }
}

// One RTDB quantity an expectation reads at every sample.
struct RtdbReader {
  std::size_t expectation = 0;
  rtdb::Database* db = nullptr;
  int agent = 0;
  int id = 0;
  std::unique_ptr<rtdb::ItemBuffer> buffer;
  rtdb::Quantity quantity;
};

std::string quantity_list(const rtdb::ItemLayout& item) {
  std::string list;
  for (const auto q : item.quantities()) list += std::string(list.empty() ? "" : ", ") + std::string(q);
  return list;
}

// The readers of the test's RTDB expectations; an expectation whose item the
// team's layout or table lacks gets its error instead.
std::vector<RtdbReader> rtdb_readers(const TestFile& test, emulator::Session& session, Record& record) {
  std::vector<RtdbReader> readers;
  for (std::size_t k = 0; k < test.expectations.size(); ++k) {
    const Expectation& x = test.expectations[k];
    if (x.check != Check::kRtdb) continue;
    const emulator::Rig& rig = session.rig(x.robot);
    emulator::LaptopLink* link = session.laptop(rig.team);
    const rtdb::ItemLayout* item = link != nullptr ? link->layout().item(x.item) : nullptr;
    if (item == nullptr) {
      record.rtdb_errors[k] = link == nullptr ? "the scenario runs without the RTDB"
                                              : "the layout " + link->layout().name() + " has no item " + x.item;
      continue;
    }
    RtdbReader r;
    if (!item->has(x.quantity)) {
      record.rtdb_errors[k] = x.item + " has no quantity " + x.quantity + " in the layout " + link->layout().name() +
                              "; it has " + quantity_list(*item);
      continue;
    }
    r.quantity = item->quantity(x.quantity);
    r.expectation = k;
    r.db = &link->database();
    r.agent = rig.agent;
    r.buffer = std::make_unique<rtdb::ItemBuffer>(*item);
    try {
      r.id = r.db->require(x.item, r.buffer->bytes().size(), r.agent);
    } catch (const SetupError& e) {
      record.rtdb_errors[k] = e.what();
      continue;
    }
    readers.push_back(std::move(r));
  }
  return readers;
}

void sample(double t, emulator::Session& session, std::vector<RtdbReader>& readers, Record& record) {
  for (std::size_t r = 0; r < session.robot_count(); ++r) {
    const kinematics::Pose p = session.world().robot(r).pose();
    record.robots[r].push_back({t, p.x_m, p.y_m});
  }
  const Eigen::Vector3d b = session.world().ball_position();
  record.ball.push_back({t, b.x(), b.y()});
  for (RtdbReader& r : readers) {
    const auto age = r.db->get(r.agent, r.agent, r.id, r.buffer->bytes());
    if (!age || *age == rtdb::Database::kNeverWritten) continue;  // nothing there yet
    record.rtdb[r.expectation].push_back({t, r.buffer->get(r.quantity), *age});
  }
}

// The bus of every robot, from the run's trace: its timing, and with a
// within_bounds expectation, every observation against the analysis' bounds.
void judge_buses(const TestFile& test, const emulator::Session& session, const std::string& trace, Record& record) {
  const auto& options = session.options();
  timing::TimingConfig config;
  config.ftt = options.ftt;
  std::vector<timing::TimingAnalyzer> analyzers;
  std::unordered_map<std::string, std::size_t> robot_of;
  for (std::size_t r = 0; r < session.robot_count(); ++r) {
    analyzers.emplace_back(options.messages, config);
    robot_of[session.rig(r).interface] = r;
  }
  bool bounded = false;
  for (const Expectation& x : test.expectations) bounded |= x.check == Check::kWithinBounds;
  std::vector<timing::BoundChecker> checkers;
  std::optional<timing::BusAnalysis> analysis;
  if (bounded) {
    timing::AnalysisConfig a;
    a.ftt = options.ftt;
    const timing::BusSet set = timing::read_bus_set(options.messages->codec().database());
    analysis = timing::analyse_bus(set, a);
    record.schedulable = analysis->schedulable();
    if (!record.schedulable) record.analysis = timing::format_analysis(*analysis);
    for (std::size_t r = 0; r < session.robot_count(); ++r) {
      checkers.emplace_back(*analysis, set.ftt ? options.messages : nullptr, Nanos{0});
    }
  }
  std::istringstream lines(trace);
  std::string line;
  frames::LogEntry e;
  while (std::getline(lines, line)) {
    if (!frames::parse_log_line(line, e)) continue;
    const auto it = robot_of.find(e.iface);
    if (it == robot_of.end()) continue;
    analyzers[it->second].add({e.frame, e.time});
    if (bounded) checkers[it->second].add({e.frame, e.time});
  }
  for (const auto& a : analyzers) record.bus.push_back(a.finish());
  for (const auto& c : checkers) record.bounds.push_back(c.finish());
}

// The run from now to `end`: each event at its time, a sample every
// elementary cycle and after each event. `Driver` has now() and
// run_until(); a ProcessStuck it throws ends the run, recorded.
template <class Driver>
void drive(const TestFile& test, emulator::Session& session, Driver& driver, Nanos end,
           std::vector<RtdbReader>& readers, Record& record) {
  const Nanos ec = session.options().ftt.elementary_cycle;
  std::size_t next_event = 0;
  sample(0, session, readers, record);
  try {
    while (driver.now() < end) {
      while (next_event < test.events.size() && from_seconds(test.events[next_event].at_s) <= driver.now()) {
        apply(test.events[next_event++], session);
      }
      Nanos next = std::min(driver.now() + ec, end);
      if (next_event < test.events.size()) next = std::min(next, from_seconds(test.events[next_event].at_s));
      driver.run_until(next);
      sample(to_seconds(driver.now()), session, readers, record);
    }
  } catch (const emulator::ProcessStuck& e) {
    record.stuck = e.what();
  }
  record.end_s = to_seconds(driver.now());
}

// The run with the team's own processes (the scenario's [external]) in
// lockstep: started, attached, driven, stopped; their output and canhil's
// word on them into `keep` when artifacts are kept. Returns the trace.
std::string run_external(const TestFile& test, const TestOptions& options, emulator::Session& session,
                         const std::filesystem::path& keep, Nanos end, std::vector<RtdbReader>& readers,
                         Record& record) {
  record.external = true;
  FILE* say = stderr;
  std::unique_ptr<FILE, int (*)(FILE*)> log(nullptr, &std::fclose);
  if (!keep.empty()) {
    log.reset(std::fopen((keep / "canhil.log").c_str(), "w"));
    if (!log) throw SetupError("cannot write " + (keep / "canhil.log").string());
    say = log.get();
  }
  external::ExternalSetup setup;
  setup.shim = options.shim;
  setup.team_preload = options.team_preload;
  setup.say = say;
  setup.spin_bus = options.alone;
  if (!keep.empty()) {
    setup.output.folder = keep.string();
  } else {
    setup.output.onto_stderr = true;
  }
  external::ExternalRun run(session, std::move(setup));
  try {
    run.start();
  } catch (const emulator::ProcessStuck& e) {
    record.stuck = e.what();
    sample(0, session, readers, record);  // what the run got to: its start
    record.end_s = 0;
  }
  if (!record.stuck) drive(test, session, run, end, readers, record);
  run.stop();
  record.ends = run.processes().ends();
  record.started = run.expected();
  return run.driver().trace();
}

void write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw SetupError("cannot write " + path.string());
}

}  // namespace

bool FileResult::passed() const noexcept { return error.empty() && failures() == 0; }

std::size_t FileResult::failures() const noexcept {
  std::size_t n = 0;
  for (const Verdict& v : verdicts) n += v.passed ? 0 : 1;
  return n;
}

FileResult run_test(const TestFile& test, const TestOptions& options) {
  const bool with_processes = options.external || test.external;
  FileResult result;
  result.file = test.path.string();
  result.name = test.name;
  const auto wall_start = std::chrono::steady_clock::now();
  try {
    emulator::SessionOptions so;
    so.messages = frames::MessageSet::create(
        frames::load_dbc(options.dbc ? std::filesystem::path(*options.dbc) : frames::default_dbc_path()));
    const std::filesystem::path keep =
        options.artifacts.empty()
            ? std::filesystem::path()
            : options.artifacts / (options.artifact_name.empty() ? test.path.stem().string() : options.artifact_name);
    if (!keep.empty()) so.world_log_period = std::chrono::milliseconds(50);
    emulator::RunOverrides o;
    if (with_processes) o.mode = emulator::RunMode::kExternal;
    o.seed = test.seed;
    o.duration_s = test.duration_s;
    o.bit_rate = test.bit_rate;
    o.faults = test.faults;
    emulator::RunPlan plan;
    try {
      plan = emulator::plan_run(test.scenario, o, so);
    } catch (const SetupError& e) {
      throw SetupError(test.path.string() + ": [test] scenario " + test.scenario.string() + ": " + e.what());
    }
    const Nanos end = from_seconds(plan.length.seconds);
    if (with_processes) external::require_told_goal(plan.scenario, false, stderr);
    emulator::Session session(std::move(plan));
    Record record;
    record.robots.resize(session.robot_count());
    for (std::size_t r = 0; r < session.robot_count(); ++r) {
      record.attacks_positive_x.push_back(session.scenario().teams[session.rig(r).team].attacks_positive_x);
      record.interfaces.push_back(session.rig(r).interface);
    }
    for (const Event& e : test.events) {
      if (from_seconds(e.at_s) >= end) {
        throw SetupError(test.path.string() + ":" + std::to_string(e.line) + ": events.at_s: " +
                         format_text("%g s is not before the run's end (%g s)", e.at_s, to_seconds(end)) +
                         ": make it earlier, or the run longer ([test] duration_s)");
      }
      if (e.robot >= session.robot_count() && (e.kind == Event::Kind::kSetPose || e.running)) {
        throw SetupError(test.path.string() + ":" + std::to_string(e.line) + ": events.robot: the scenario has " +
                         std::to_string(session.robot_count()) + " robot(s), numbered from 0");
      }
    }
    for (const Expectation& x : test.expectations) {
      if (x.robot >= session.robot_count()) {
        throw SetupError(test.path.string() + ":" + std::to_string(x.line) + ": expect.robot: the scenario has " +
                         std::to_string(session.robot_count()) + " robot(s), numbered from 0");
      }
    }
    std::vector<RtdbReader> readers = rtdb_readers(test, session, record);
    std::string trace;
    if (with_processes) {
      if (!keep.empty()) std::filesystem::create_directories(keep);
      trace = run_external(test, options, session, keep, end, readers, record);
      record.latencies.resize(session.robot_count());  // the team's handler's are its own: none here
    } else {
      emulator::VirtualDriver driver(session);
      drive(test, session, driver, end, readers, record);
      for (std::size_t r = 0; r < session.robot_count(); ++r) {
        const laptop::HwComm* hw = driver.handler(r);
        record.latencies.push_back(hw != nullptr ? hw->stats().latencies : std::vector<Nanos>{});
      }
      trace = driver.trace();
    }
    result.virtual_s = record.end_s;
    record.goals = session.goals();
    judge_buses(test, session, trace, record);
    if (!keep.empty()) {
      std::filesystem::create_directories(keep);
      write(keep / "trace.log", trace);
      write(keep / "world.csv", session.world_log());
      result.artifacts = keep.string();
      record.where = "the trace " + (keep / "trace.log").string() + " and world log " + (keep / "world.csv").string();
    } else {
      record.where = "the trace and world log: run again with --artifacts DIR";
    }
    for (const Expectation& x : test.expectations) result.verdicts.push_back(detail::judge(x, test, record));
    if (!keep.empty()) write(keep / "verdicts.txt", format_result(result));
  } catch (const SetupError& e) {
    result.error = e.what();
  } catch (const std::exception& e) {
    result.error = test.path.string() + ": " + e.what();
  }
  if (!result.error.empty()) result.verdicts.clear();  // a file that could not run is one error, whole
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

FileResult run_test_file(const std::filesystem::path& path, const TestOptions& options) {
  try {
    return run_test(load_test_file(path), options);
  } catch (const std::exception& e) {
    FileResult r;
    r.file = path.string();
    r.name = path.stem().string();
    r.error = e.what();
    return r;
  }
}

}  // namespace canhil::verdict
