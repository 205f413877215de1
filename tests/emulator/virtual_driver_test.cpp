// A session in virtual time (the virtual driver): emulated nodes and physics,
// the reference handler and agent, the emulated vision; deterministic,
// FTT-clean, and the robot serves its purpose: it finds the ball and kicks it
// towards the goal.
#include "canhil/emulator/virtual_driver.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "canhil/emulator/scenario.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/physics/config.hpp"
#include "canhil/rtdb/rtdb.h"
#include "canhil/timing/analysis.hpp"
#include "canhil/timing/bound_check.hpp"
#include "canhil/timing/bus_analysis.hpp"
#include "rtdb_user.h"
#include "support/counter_watch.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

struct Config {
  Scenario scenario;
  SessionOptions options;
  VirtualOptions virtual_options;
};

// A session and its virtual driver, as canhil run --virtual-time builds them.
// Every robot's nodes and handler are watched: a counter that moves without
// the test saying so fails it when the loop ends.
class Loop {
 public:
  explicit Loop(const Config& c, test::CounterWatch* watch = nullptr)
      : session_(plan_run(c.scenario, c.options)), driver_(session_, c.virtual_options), watch_(watch) {
    if (watch_ == nullptr) return;
    for (std::size_t r = 0; r < session_.robot_count(); ++r) {
      const std::string p = "robot" + std::to_string(r) + ".";
      watch_->watch_nodes(*session_.rig(r).nodes, p);
      if (const laptop::HwComm* hw = driver_.handler(r)) {
        watch_->watch(p + "handler.wrong_length", [hw] { return hw->stats().wrong_length; });
        watch_->watch(p + "handler.out_of_range", [hw] { return hw->stats().out_of_range; });
        watch_->watch(p + "handler.unknown_id", [hw] { return hw->stats().unknown_id; });
        watch_->watch(p + "handler.missed_tms", [hw] { return hw->stats().missed_tms; });
        watch_->watch(p + "handler.send_failed", [hw] { return hw->stats().send_failed; });
      }
    }
  }
  ~Loop() {
    if (watch_ != nullptr) watch_->finish();
  }
  Loop(const Loop&) = delete;
  Loop& operator=(const Loop&) = delete;
  void run_for(Nanos d) { driver_.run_for(d); }
  std::string trace() const { return driver_.trace(); }
  const physics::World& world() const { return session_.world(); }
  std::vector<RobotOutcome> outcomes() const { return driver_.outcomes(); }
  const std::vector<Goal>& goals() const { return session_.goals(); }
  const std::string& world_log() const { return session_.world_log(); }
  std::vector<can_nodes::FaultCount> fault_counts() const { return session_.fault_counts(); }
  Session& session() { return session_; }
  const laptop::HwComm* handler(std::size_t robot) const { return driver_.handler(robot); }

 private:
  Session session_;
  VirtualDriver driver_;
  test::CounterWatch* watch_;
};

class VirtualRunTest : public test::WatchedTest {
 protected:
  void SetUp() override {
    static int counter = 0;
    setenv("RTDB_KEY", std::to_string(0x59000000 + ((getpid() & 0xFFF) << 12) + (++counter << 6)).c_str(), 1);
  }
  static Config one_robot() {
    Config c;
    c.options.messages = frames::MessageSet::load(test::shipped_dbc());
    c.scenario.world.robots = {physics::Placement{-3.0, 0.0, -90}};  // facing the opponent goal (+x)
    c.scenario.world.ball_start = {-1.0, 1.0, c.scenario.world.ball.radius_m};
    c.scenario.bus.bit_rate = 0;  // the instant bus these tests judge (a run's default is the DBC's Baudrate)
    return c;
  }
  // The same on a timed wire at 1 Mbit/s ([bus] bit_rate): frames take their
  // bits and are stamped at their end of frame, and the FTT master and slaves
  // keep their windows from those stamps (frames::ec_start).
  static Config on_the_wire() {
    Config c = one_robot();
    c.scenario.bus.bit_rate = 1'000'000;
    return c;
  }
  // The trace of a run of `c` for `d`, its nodes and handler watched.
  std::string trace_after(const Config& c, Nanos d) {
    Loop run(c, &counters);
    run.run_for(d);
    return run.trace();
  }
};

TEST_F(VirtualRunTest, SameScenarioSameTraceByteForByte) {
  const std::string first = trace_after(one_robot(), 3s);
  EXPECT_EQ(trace_after(one_robot(), 3s), first);
  EXPECT_GT(first.size(), 50'000u);
}

TEST_F(VirtualRunTest, ItemAgesAreInTheRunsVirtualTime) {
  // Two seconds of virtual time take milliseconds of real time: ages read by
  // the wall clock would all be about 0.
  Loop run(one_robot(), &counters);
  run.run_for(2s);
  std::vector<char> item(static_cast<std::size_t>(DB_item_size(VISION_INFO)));
  const int vision_age = DB_get_from(CAMBADA_1, CAMBADA_1, VISION_INFO, item.data());
  EXPECT_GE(vision_age, 0);
  EXPECT_LE(vision_age, 34) << "written at 30 Hz";
  item.resize(static_cast<std::size_t>(DB_item_size(CMD_SETPOSE)));
  EXPECT_NEAR(DB_get_from(CAMBADA_1, CAMBADA_1, CMD_SETPOSE, item.data()), 2000, 15)
      << "written at the start only (the handler takes the pose at its first TM)";
}

TEST_F(VirtualRunTest, WithoutATraceFramesAreCountedNotKept) {
  Config c = one_robot();
  c.virtual_options.record_trace = false;
  Loop run(c, &counters);
  run.run_for(1s);
  EXPECT_TRUE(run.trace().empty());
  EXPECT_GT(run.outcomes()[0].frames, 500u);
}

TEST_F(VirtualRunTest, TheTraceIsFttCompliant) {
  Loop run(one_robot(), &counters);
  run.run_for(4s);
  const Config cfg = one_robot();
  timing::TimingAnalyzer analyzer(cfg.options.messages, timing::TimingConfig{});
  std::istringstream in(run.trace());
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    ASSERT_TRUE(frames::parse_log_line(line, e));
    analyzer.add({e.frame, e.time});
  }
  const timing::TimingReport report = analyzer.finish();
  EXPECT_TRUE(report.ok()) << timing::format_table(report);
  EXPECT_EQ(report.unknown, 0u);
  EXPECT_EQ(run.outcomes()[0].bad_frames, 0u);
}

std::vector<frames::TimedFrame> frames_of(const std::string& trace) {
  std::vector<frames::TimedFrame> out;
  std::istringstream in(trace);
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    EXPECT_TRUE(frames::parse_log_line(line, e)) << line;
    out.push_back({e.frame, e.time});
  }
  return out;
}

TEST_F(VirtualRunTest, OnATimedWireFramesTakeTheirBitsAndStayInsideEveryBoundOfTheAnalysis) {
  Loop run(on_the_wire(), &counters);
  run.run_for(3s);
  const std::vector<frames::TimedFrame> seen = frames_of(run.trace());
  ASSERT_GT(seen.size(), 1500u);
  // One frame at a time: each ends at least its own wire time (less the
  // intermission) after the previous one.
  for (std::size_t i = 1; i < seen.size(); ++i) {
    ASSERT_GE(seen[i].time - seen[i - 1].time, frames::bits_to_time(frames::frame_bits(seen[i].frame) - 3, 1'000'000))
        << "frame " << i;
  }
  timing::AnalysisConfig config;
  config.ftt.stamps = frames::StampAt::kEndOfFrame;
  const timing::BusAnalysis analysis =
      timing::analyse_bus(timing::read_bus_set(frames::load_dbc(test::shipped_dbc())), config);
  timing::BoundChecker check(analysis, on_the_wire().options.messages, Nanos{0});
  timing::TimingConfig ftt;
  ftt.ftt.stamps = frames::StampAt::kEndOfFrame;
  timing::TimingAnalyzer analyzer(on_the_wire().options.messages, ftt);
  for (const frames::TimedFrame& f : seen) {
    check.add(f);
    analyzer.add(f);
  }
  const timing::BoundReport bounds = check.finish();
  EXPECT_TRUE(bounds.ok()) << timing::format_bounds(bounds);
  EXPECT_TRUE(analyzer.finish().ok()) << timing::format_table(analyzer.finish());
  // Responses are not zero on a wire: each synchronous frame of an EC ends after the one before it.
  Nanos latest_in_window{0};
  for (const timing::Observation& o : bounds.observations) {
    if (o.quantity == timing::Bounded::kEndInWindow && o.count > 0)
      latest_in_window = std::max(latest_in_window, o.most);
  }
  EXPECT_GT(latest_in_window, 1ms) << "the EC's last synchronous frame ends over a millisecond into the window";
}

TEST_F(VirtualRunTest, OnATimedWireTheSameScenarioGivesTheSameTrace) {
  const std::string first = trace_after(on_the_wire(), 2s);
  EXPECT_EQ(trace_after(on_the_wire(), 2s), first);
  EXPECT_NE(first, trace_after(one_robot(), 2s)) << "the wire moves frames: not the instant bus's trace";
}

TEST_F(VirtualRunTest, TheLaptopsControllerBusOffBrakesTheRobotAndItsRestartResumesIt) {
  // The handler's controller goes bus-off at 1 s (busoff:laptop), restarts
  // 800 ms later and recovers 128 x 11 recessive bits after: Pic_base hears
  // no M6 for more than its 150 ms watchdog and brakes, while the same run
  // without the fault drives on; after the restart the robot drives again.
  auto distance = [&](Loop& run, Nanos& now, Nanos from, Nanos to) {
    run.run_for(from - now);
    const kinematics::Pose a = run.outcomes()[0].pose;
    run.run_for(to - from);
    now = to;
    const kinematics::Pose b = run.outcomes()[0].pose;
    return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
  };
  Config c = on_the_wire();
  c.scenario.bus.restart_ms = 800;
  Loop healthy(c);
  Nanos healthy_now{0};
  const double healthy_moved = distance(healthy, healthy_now, 1600ms, 1780ms);
  c.scenario.faults.push_back(can_nodes::parse_fault("busoff:laptop@1"));
  Loop run(c, &counters);
  counters.allow("robot0.handler.send_failed");  // its queue fills while it is bus-off
  counters.allow("robot0.handler.missed_tms");   // it hears no TM then
  Nanos now{0};
  EXPECT_GT(distance(run, now, 700ms, 900ms), 0.05) << "driving to the ball before";
  EXPECT_GT(healthy_moved, 0.05) << "without the fault it drives on";
  EXPECT_LT(distance(run, now, 1600ms, 1780ms), 0.001) << "braked: no M6 for longer than the watchdog";
  EXPECT_GT(distance(run, now, 1900ms, 2100ms), 0.05) << "restarted at 1.8 s and recovered: driving again";
  std::istringstream trace(run.trace());
  std::string line;
  int bus_off = 0, restarted = 0;
  while (std::getline(trace, line)) {
    bus_off += line.find(" 20000240#") != std::string::npos ? 1 : 0;    // CAN_ERR_BUSOFF | CAN_ERR_CNT
    restarted += line.find(" 20000300#") != std::string::npos ? 1 : 0;  // CAN_ERR_RESTARTED | CAN_ERR_CNT
  }
  EXPECT_EQ(bus_off, 1);
  EXPECT_EQ(restarted, 1);
  // The handler heard its controller say so (it asks for error frames, as canhil-hwcomm does).
  ASSERT_NE(run.handler(0), nullptr);
  EXPECT_EQ(run.handler(0)->stats().bus_offs, 1u);
  EXPECT_EQ(run.handler(0)->stats().restarts, 1u);
  EXPECT_EQ(run.handler(0)->stats().controller, laptop::ControllerState::kErrorActive);
}

TEST_F(VirtualRunTest, TheRobotFindsTheBallAndKicksItTowardsTheGoal) {
  Loop run(one_robot(), &counters);
  const double start_x = run.world().ball_position().x();
  bool kicked = false;
  for (int second = 0; second < 30 && !kicked; ++second) {
    run.run_for(1s);
    kicked = run.outcomes()[0].kicks > 0;
  }
  ASSERT_TRUE(kicked) << "the agent never kicked; robot at (" << run.outcomes()[0].pose.x_m << ", "
                      << run.outcomes()[0].pose.y_m << "), ball at (" << run.world().ball_position().x() << ", "
                      << run.world().ball_position().y() << ")";
  run.run_for(2s);
  const Eigen::Vector3d ball = run.world().ball_position();
  EXPECT_GT(ball.x(), start_x + 3.0) << "the ball went towards the opponent goal (+x)";
  run.run_for(3s);
  ASSERT_EQ(run.goals().size(), 1u) << "the reference agent scores from this start";
  EXPECT_TRUE(run.goals()[0].positive_x);
  EXPECT_LT(std::fabs(ball.y()), 3.0);
}

TEST_F(VirtualRunTest, TheReferenceLaptopWorksInTheTeamsLayout) {
  // canhil's RTDB described by another layout: CMD_VEL's velocities as whole
  // mm/s in 32-bit integers. The reference handler and agent both go through the layout, so the loop
  // still closes and the robot still scores; the bytes say which layout wrote them.
  std::ifstream in(test::source_dir() + "/rtdb/layouts/canhil.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string layout = text.str();
  const auto replace = [&layout](const std::string& from, const std::string& to) {
    const auto at = layout.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    layout.replace(at, from.size(), to);
  };
  replace(R"(vx = { type = "f32", offset = 0, from = "vx", unit = "m/s" })",
          R"(vx = { type = "i32", offset = 0, from = "vx", unit = "mm/s" })");
  replace(R"(vy = { type = "f32", offset = 4, from = "vy", unit = "m/s" })",
          R"(vy = { type = "i32", offset = 4, from = "vy", unit = "mm/s" })");
  replace(R"(name = "canhil")", R"(name = "integers")");
  const std::string file = "/tmp/canhil-integers-layout-" + std::to_string(getpid()) + ".toml";
  std::ofstream(file) << layout;
  Config c = one_robot();
  c.scenario.laptop.layout = file;
  Loop run(c, &counters);
  run.run_for(1s);  // on its way to the ball
  ASSERT_EQ(DB_init_all(0), 0);
  std::int32_t vel[4] = {};
  ASSERT_GE(DB_get_from(CAMBADA_1, CAMBADA_1, CMD_VEL, vel), 0);
  DB_free_all(0);
  const double speed_mm_s = std::hypot(vel[0], vel[1]);
  EXPECT_GT(speed_mm_s, 50) << "whole mm/s: the agent wrote through the team's layout";
  EXPECT_LT(speed_mm_s, 5000);
  run.run_for(9s);
  std::filesystem::remove(file);
  ASSERT_EQ(run.goals().size(), 1u) << "the reference laptop plays in the team's layout";
  EXPECT_TRUE(run.goals()[0].positive_x);
}

TEST_F(VirtualRunTest, TheReferenceAgentWaitsForTheCoachsStart) {
  Config c = one_robot();
  c.scenario.coach.game_state = "stop";
  Loop run(c, &counters);
  const kinematics::Pose before = run.outcomes()[0].pose;
  run.run_for(3s);
  const kinematics::Pose stopped = run.outcomes()[0].pose;
  EXPECT_NEAR(stopped.x_m, before.x_m, 0.01) << "stop: the robot stands";
  EXPECT_NEAR(stopped.y_m, before.y_m, 0.01);
  EXPECT_EQ(run.outcomes()[0].kicks, 0);
  run.session().apply(SetCoach{"start", std::nullopt, std::nullopt, std::nullopt, std::nullopt});
  bool kicked = false;
  for (int second = 0; second < 30 && !kicked; ++second) {
    run.run_for(1s);
    kicked = run.outcomes()[0].kicks > 0;
  }
  EXPECT_TRUE(kicked) << "start: it plays";
}

timing::TimingReport analyse(const std::string& trace, const std::shared_ptr<const frames::MessageSet>& set,
                             const std::string& iface) {
  timing::TimingAnalyzer analyzer(set, timing::TimingConfig{});
  std::istringstream in(trace);
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    if (!frames::parse_log_line(line, e)) ADD_FAILURE() << line;
    if (e.iface == iface) analyzer.add({e.frame, e.time});
  }
  return analyzer.finish();
}

TEST_F(VirtualRunTest, TheFiveRobotScenarioRunsWithEveryLoopClosed) {
  const Scenario sc = load_scenario(test::source_dir() + "/emulator/scenarios/five_robots.toml");
  ASSERT_EQ(sc.world.robots.size(), 5u);
  ASSERT_EQ(sc.world.obstacles.size(), 5u);
  Config c = one_robot();
  c.scenario.world = sc.world;
  c.scenario.interfaces = sc.interfaces;
  c.scenario.agents = sc.agents;
  c.options.world_log_period = 100ms;
  Loop run(c, &counters);
  run.run_for(6s);
  const auto outcomes = run.outcomes();
  const std::string trace = run.trace();
  // Every robot: its agent's commands moved it (it drove or turned), and its
  // handler's odometry (CMD_POS, in the world log) followed the true pose.
  std::istringstream log(run.world_log());
  std::string line;
  std::getline(log, line);
  EXPECT_EQ(line.rfind("time_s,ball_x_m", 0), 0u) << line;
  std::vector<std::vector<double>> rows;
  while (std::getline(log, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::stod(cell));
    ASSERT_EQ(row.size(), 4u + 6u * 5u) << line;
    rows.push_back(row);
  }
  ASSERT_GE(rows.size(), 55u);
  for (std::size_t r = 0; r < 5; ++r) {
    SCOPED_TRACE("robot " + std::to_string(r));
    const std::size_t k = 4 + 6 * r;
    double travel = 0, turned = 0, worst = 0;
    for (std::size_t i = 1; i < rows.size(); ++i) {
      travel += std::hypot(rows[i][k] - rows[i - 1][k], rows[i][k + 1] - rows[i - 1][k + 1]);
      turned += std::fabs(std::remainder(rows[i][k + 2] - rows[i - 1][k + 2], 360.0));
      worst = std::max(worst, std::hypot(rows[i][k] - rows[i][k + 3], rows[i][k + 1] - rows[i][k + 4]));
    }
    EXPECT_TRUE(travel > 0.5 || turned > 90) << "travel " << travel << " m, turned " << turned << " deg";
    EXPECT_LT(worst, 0.25) << "the reported pose strayed from the true one";
    EXPECT_EQ(outcomes[r].bad_frames, 0u);
    EXPECT_GT(outcomes[r].frames, 3000u);
    const timing::TimingReport report = analyse(trace, c.options.messages, sc.interfaces[r]);
    EXPECT_TRUE(report.ok()) << timing::format_table(report);
  }
}

TEST_F(VirtualRunTest, TheFiveRobotScenarioPlaysOnAfterAGoal) {
  // Its referee restarts play with a kick-off. Without one, the ball lay where
  // the net threw it back, (8.60, 0.00), 8.8 m from the nearest robot and
  // beyond every camera's 5 m: the five robots turned on the spot to the end.
  Config c = one_robot();
  c.scenario = load_scenario(test::source_dir() + "/emulator/scenarios/five_robots.toml");
  Loop run(c, &counters);
  run.run_for(20s);
  ASSERT_GE(run.goals().size(), 2u) << "a goal, the kick-off, and another goal";
  const Referee* referee = run.session().referee();
  ASSERT_NE(referee, nullptr);
  ASSERT_FALSE(referee->calls().empty());
  EXPECT_EQ(referee->calls().front().restart, Restart::kKickoff);
  EXPECT_EQ(referee->calls().front().time, run.goals().front().time);
  EXPECT_GE(run.outcomes()[0].kicks, 2) << "robot 0 played the ball again";
}

TEST_F(VirtualRunTest, FaultsHaveTheirEffectAndTheSameSeedRepeatsThem) {
  Config c = one_robot();
  c.scenario.faults = {can_nodes::parse_fault("drop:M4_1:0.5"), can_nodes::parse_fault("silence:Motor2:1")};
  c.scenario.seed = 7;
  std::string first;
  std::vector<can_nodes::FaultCount> counts;
  {
    Loop run(c, &counters);
    run.run_for(2s);
    first = run.trace();
    counts = run.fault_counts();
    // What the rules did, and nothing else.
    counters.expect("robot0.Pic_odom.fault_dropped", counts.at(0).applied);
    counters.expect("robot0.Motor2.fault_dropped", counts.at(1).applied);
  }
  ASSERT_EQ(counts.size(), 2u);
  EXPECT_EQ(counts[1].applied, counts[1].matched);
  EXPECT_GT(counts[1].applied, 50u);
  const frames::MessageSet& set = *c.options.messages;
  const std::uint32_t m4_1 = set.codec().find("M4_1")->id();
  const std::uint32_t m3_2 = set.codec().find("M3_2")->id();
  std::size_t m4_seen = 0, m3_2_before = 0, m3_2_after = 0;
  std::istringstream in(first);
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    ASSERT_TRUE(frames::parse_log_line(line, e));
    if (e.frame.id == m4_1) ++m4_seen;
    if (e.frame.id == m3_2) (e.time < 1s ? m3_2_before : m3_2_after) += 1;
  }
  EXPECT_EQ(m4_seen + counts[0].applied, counts[0].matched) << "every dropped M4_1 is missing from the bus";
  EXPECT_GT(counts[0].applied, counts[0].matched / 3);
  EXPECT_LT(counts[0].applied, counts[0].matched * 2 / 3);
  EXPECT_GT(m3_2_before, 10u);
  EXPECT_EQ(m3_2_after, 0u) << "Motor2 is silent from 1 s on";
  // The timing report sees the faults: M4_1 frames missing, M3_2 missing.
  const timing::TimingReport report = analyse(first, c.options.messages, "vcan0");
  EXPECT_FALSE(report.ok());
  Loop again(c, &counters);
  counters.expect("robot0.Pic_odom.fault_dropped", counts[0].applied);
  counters.expect("robot0.Motor2.fault_dropped", counts[1].applied);
  again.run_for(2s);
  EXPECT_EQ(again.trace(), first) << "same scenario and seed, same faults";
}

TEST_F(VirtualRunTest, ErrorFramesGoOnTheBusAndTheFrameIsSentAgainAfter) {
  Config c = one_robot();
  c.scenario.faults = {can_nodes::parse_fault("error:M3_1:0.2")};
  Loop run(c, &counters);
  run.run_for(2s);
  const auto counts = run.fault_counts();
  ASSERT_EQ(counts.size(), 1u);
  counters.expect("robot0.Motor1.error_frames", counts[0].applied);
  EXPECT_GT(counts[0].applied, counts[0].matched / 10);
  EXPECT_LT(counts[0].applied, counts[0].matched * 3 / 10);
  const std::uint32_t m3_1 = c.options.messages->codec().find("M3_1")->id();
  std::size_t errors = 0, m3_seen = 0, retransmitted = 0;
  Nanos last_error{-1};
  std::istringstream in(run.trace());
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    ASSERT_TRUE(frames::parse_log_line(line, e)) << line;
    if (e.frame.kind == frames::FrameKind::kError) {
      ++errors;
      EXPECT_EQ(e.frame.id, frames::kErrorClassProtocol | frames::kErrorClassBusError) << line;
      last_error = e.time;
    } else if (e.frame.id == m3_1) {
      ++m3_seen;
      // The retransmission follows its error frame by the frame's and the error frame's bits.
      if (last_error >= Nanos{0} && e.time - last_error < 1ms) ++retransmitted;
    }
  }
  EXPECT_EQ(errors, counts[0].applied) << "every error frame is in the trace";
  EXPECT_EQ(m3_seen, counts[0].matched) << "no frame is lost: the controller sends it again";
  EXPECT_EQ(retransmitted, counts[0].applied);
  const timing::TimingReport report = analyse(run.trace(), c.options.messages, "vcan0");
  EXPECT_EQ(report.error_frames, errors);
  for (const timing::MessageTiming& m : report.messages) {
    EXPECT_EQ(m.violations.count(timing::ViolationKind::kMissing), 0u) << m.name << "\n"
                                                                       << timing::format_table(report);
  }
}

TEST_F(VirtualRunTest, ABatteryFaultDrainsThePackTheSystemMonitorReports) {
  // M2's v_power24 over a run: full, then from 1 s on 20 % of the pack a second.
  auto power24 = [&](std::vector<std::string> rules) {
    Config c = one_robot();
    for (const auto& r : rules) c.scenario.faults.push_back(can_nodes::parse_fault(r));
    Loop run(c, &counters);
    run.run_for(5s);
    const frames::MessageCodec& m2 = *c.options.messages->codec().find("M2");
    const std::size_t v24 = *m2.index_of("v_power24");
    std::vector<std::pair<double, double>> volts;  // (time, V)
    std::istringstream in(run.trace());
    std::string line;
    while (std::getline(in, line)) {
      frames::LogEntry e;
      EXPECT_TRUE(frames::parse_log_line(line, e));
      if (e.frame.kind != frames::FrameKind::kData || e.frame.id != m2.id()) continue;
      std::vector<double> v(m2.signal_count());
      EXPECT_EQ(m2.decode(e.frame, v).status, frames::DecodeStatus::kOk);
      volts.emplace_back(to_seconds(e.time), v[v24]);
    }
    const auto outcome = run.outcomes().at(0);
    return std::make_tuple(volts, outcome.charge, run.fault_counts());
  };
  const auto [healthy, healthy_charge, none] = power24({});
  const auto [draining, charge, counts] = power24({"battery:power24:20@1"});
  ASSERT_GE(healthy.size(), 4u) << "M2 every second";
  ASSERT_EQ(healthy.size(), draining.size());
  for (std::size_t k = 0; k < healthy.size(); ++k) {
    const double t = healthy[k].first;
    ASSERT_DOUBLE_EQ(draining[k].first, t);
    EXPECT_GT(healthy[k].second, 24.0);
    // 20 % of the pack a second from 1 s on; the pack spans 21.0 to 25.2 V.
    const double expected = 0.2 * std::max(0.0, t - 1.0) * (25.2 - 21.0);
    EXPECT_NEAR(healthy[k].second - draining[k].second, expected, 0.1) << "at " << t << " s";
  }
  EXPECT_GT(healthy.back().second - draining.back().second, 2.0) << "visibly low by the end";
  EXPECT_NEAR(healthy_charge[2] - charge[2], 0.8, 0.01) << "4 s at 20 %";
  EXPECT_NEAR(charge[0], healthy_charge[0], 1e-9) << "only the 24 V pack";
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_NEAR(to_seconds(counts[0].active), 4.0, 0.02);
}

}  // namespace
}  // namespace canhil::emulator
