// The emulated nodes against a fake robot, on the memory bus, in virtual time:
// the FTT schedule, both sides of its time boundaries, and bad traffic.
#include "canhil/can_nodes/nodes.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/robot_nodes.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "support/counter_watch.hpp"
#include "support/laptop_endpoint.hpp"
#include "support/node_rig.hpp"
#include "support/test_paths.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

using test::FakeRobot;

class NodesTest : public test::WatchedTest {
 protected:
  NodesTest() { counters.watch_nodes(nodes_); }
  std::vector<frames::Tm> tms() const { return laptop_.decoded(set_->tm); }
  Nanos window_start(std::size_t ec) const {
    const auto tm = laptop_.with_id(set_->tm.message().id()).at(ec);
    frames::Tm t;
    set_->tm.decode(tm.frame, t);
    return frames::sync_window_start(t, tm.time, params_.ftt.elementary_cycle);
  }

  test::NodeRig rig_;
  const std::shared_ptr<const frames::MessageSet>& set_ = rig_.set;
  const NodeParams& params_ = rig_.params;
  FakeRobot& robot_ = rig_.robot;
  RobotNodes& nodes_ = rig_.nodes;
  test::LaptopEndpoint& laptop_ = rig_.laptop;
  VirtualTime& run_ = rig_.run;
  const SimulatedClock& clock_ = rig_.clock;
};

TEST_F(NodesTest, TriggerMessageExactlyEveryElementaryCycle) {
  run_.run_until(995ms);
  const auto frames = laptop_.with_id(set_->tm.message().id());
  ASSERT_EQ(frames.size(), 100u);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    EXPECT_EQ(frames[k].time, Nanos{static_cast<std::int64_t>(k) * 10'000'000}) << k;
    frames::Tm tm;
    ASSERT_TRUE(set_->tm.decode(frames[k].frame, tm).ok());
    EXPECT_EQ(tm.ec_counter, k);
  }
}

TEST_F(NodesTest, BitmapSchedulesEachMessageAtItsPeriod) {
  run_.run_until(295ms);
  const auto t = tms();
  ASSERT_EQ(t.size(), 30u);
  for (std::size_t k = 0; k < t.size(); ++k) {
    const std::uint32_t b = t[k].sync_bitmap;
    const bool third = k % 3 == 0;
    const bool fifth = k % 5 == 0;
    EXPECT_EQ((b >> 0) & 1u, third ? 1u : 0u) << "M1, EC " << k;
    for (int i : {1, 2, 3}) EXPECT_EQ((b >> i) & 1u, 1u) << "M3, EC " << k;
    EXPECT_EQ((b >> 4) & 1u, fifth ? 1u : 0u) << "M4_1, EC " << k;
    EXPECT_EQ((b >> 5) & 1u, fifth ? 1u : 0u) << "M4_2, EC " << k;
    EXPECT_EQ((b >> 6) & 1u, third ? 1u : 0u) << "M6_1, EC " << k;
    EXPECT_EQ((b >> 7) & 1u, third ? 1u : 0u) << "M6_2, EC " << k;
    EXPECT_EQ((b >> 8) & 1u, fifth ? 1u : 0u) << "M8, EC " << k;
    EXPECT_EQ((b >> 9) & 1u, third ? 1u : 0u) << "M9, EC " << k;
    // Window: worst-case wire time of what is due (135 us per frame at 1 Mbit/s) plus the guard.
    EXPECT_EQ(t[k].sync_window_us, std::popcount(b) * 135 + 20) << k;
  }
}

TEST_F(NodesTest, SynchronousFramesOnlyWhenScheduledAndInsideTheWindow) {
  laptop_.m6_1 = frames::M6_1{0, 0.5};
  run_.run_until(600ms - 1ns);  // through the end of EC 59
  const auto tm_frames = laptop_.with_id(set_->tm.message().id());
  std::map<std::uint32_t, int> counts;
  for (const auto& f : laptop_.frames()) {
    const frames::MessageCodec* m = set_->codec().find(f.frame.id);
    ASSERT_NE(m, nullptr);
    const frames::FttInfo& info = set_->ftt(*m);
    if (info.kind != frames::FttKind::kSync) continue;
    const auto k = static_cast<std::size_t>(f.time / 10ms);
    frames::Tm tm;
    ASSERT_TRUE(set_->tm.decode(tm_frames.at(k).frame, tm).ok());
    EXPECT_TRUE((tm.sync_bitmap >> info.index) & 1u) << m->name() << " in EC " << k << " which does not schedule it";
    EXPECT_GE(f.time, window_start(k)) << m->name() << " before the synchronous window";
    EXPECT_LT(f.time, tm_frames.at(k).time + 10ms) << m->name() << " after the EC";
    ++counts[f.frame.id];
  }
  // Over 60 ECs: M3 in each, M1/M6/M9 in every 3rd (the laptop's own M6 are not
  // heard by itself), M4/M8 in every 5th.
  EXPECT_EQ(counts[0x111], 60);
  EXPECT_EQ(counts[0x112], 60);
  EXPECT_EQ(counts[0x113], 60);
  EXPECT_EQ(counts[0x100], 20);
  EXPECT_EQ(counts[0x151], 20);
  EXPECT_EQ(counts[0x121], 12);
  EXPECT_EQ(counts[0x122], 12);
  EXPECT_EQ(counts[0x141], 12);
}

TEST_F(NodesTest, BothSidesOfTheM1Boundary) {
  run_.run_until(10ms);  // EC 1 has begun; EC 3 carries the second M1
  run_.run_until(30ms);
  const Nanos start3 = window_start(3);
  run_.run_until(start3 - 1ns);
  EXPECT_EQ(laptop_.with_id(0x100).size(), 1u) << "just before EC 3's window: only EC 0's M1";
  run_.run_until(start3);
  ASSERT_EQ(laptop_.with_id(0x100).size(), 2u) << "at the window start: the frame";
  EXPECT_EQ(laptop_.with_id(0x100)[1].time, start3);
}

TEST_F(NodesTest, AsynchronousFramesRespectTheirMinimumGap) {
  run_.run_until(5s);
  const auto m2 = laptop_.with_id(0x200);
  const auto m10 = laptop_.with_id(0x210);
  ASSERT_EQ(m2.size(), 5u);
  ASSERT_EQ(m10.size(), 5u);
  for (std::size_t i = 1; i < m2.size(); ++i) EXPECT_GE(m2[i].time - m2[i - 1].time, 1s);
  for (const auto& f : m2) {
    const Nanos in_ec = f.time % 10ms;
    EXPECT_GT(in_ec, Nanos{0}) << "after the TM";
    EXPECT_LT(in_ec, 10ms - 1485us) << "before the largest synchronous window";
  }
}

TEST_F(NodesTest, PicBaseTurnsM6IntoSaturatedSetPointsAndTheWatchdogBrakes) {
  laptop_.m6_1 = frames::M6_1{0, 10.0};  // far beyond what the wheels can do
  run_.run_until(1s);
  const auto m1 = laptop_.decoded(set_->m1);
  ASSERT_FALSE(m1.empty());
  EXPECT_EQ(m1.back().setpoint_1, 900) << "saturated";
  EXPECT_EQ(m1.back().setpoint_2, -900);
  EXPECT_EQ(m1.back().setpoint_3, 0);
  EXPECT_EQ(m1.back().enable, 1);
  // The ramp: set points climb by at most the acceleration limit times the time
  // between two M1 (about 30 ms; the window's start depends on the EC's load).
  const auto m1_frames = laptop_.with_id(0x100);
  for (std::size_t i = 2; i < 6; ++i) {
    const double dt = std::chrono::duration<double>(m1_frames[i].time - m1_frames[i - 1].time).count();
    const double step = params_.encoder.counts_per_tick(params_.max_wheel_accel_radps2) * dt;
    EXPECT_LE(std::abs(m1[i].setpoint_1 - m1[i - 1].setpoint_1), step + 1) << i;
    EXPECT_GE(std::abs(m1[i].setpoint_1 - m1[i - 1].setpoint_1), step - 1) << "climbs at the limit " << i;
  }
  // Motors apply the set point at their tick.
  EXPECT_NEAR(robot_.speed[0], params_.encoder.wheel_radps(900), 1e-9);
  // Silence: within the watchdog time (plus one M1 period) M1 brakes.
  laptop_.m6_1.reset();
  const Nanos silent_from = clock_.now();
  run_.run_until(silent_from + 200ms);
  const auto after = laptop_.with_id(0x100);
  Nanos braked_at = kNever;
  for (const auto& f : after) {
    frames::M1 v;
    set_->m1.decode(f.frame, v);
    if (f.time > silent_from && v.enable == 0 && braked_at == kNever) {
      braked_at = f.time;
      EXPECT_EQ(v.setpoint_1, 0);
      EXPECT_EQ(v.setpoint_2, 0);
    }
  }
  ASSERT_NE(braked_at, kNever);
  EXPECT_LE(braked_at - silent_from, params_.watchdog + 30ms);
  EXPECT_GT(braked_at - silent_from, params_.watchdog - 30ms) << "not before the watchdog time";
  EXPECT_EQ(robot_.speed[0], 0.0);
}

TEST_F(NodesTest, BrakesFromStartUntilTheFirstM6) {
  run_.run_until(100ms);
  const auto m1 = laptop_.decoded(set_->m1);
  ASSERT_FALSE(m1.empty());
  for (const auto& v : m1) {
    EXPECT_EQ(v.enable, 0) << "no M6 heard yet: the watchdog holds the brake";
    EXPECT_EQ(v.setpoint_1, 0);
  }
  EXPECT_TRUE(nodes_.pic_base().watchdog_tripped(clock_.now()));
  const auto m9 = laptop_.decoded(set_->m9);
  ASSERT_FALSE(m9.empty());
  EXPECT_EQ(m9.back().just_kicked, 0) << "never kicked";
}

TEST_F(NodesTest, KickOnlyWhenEngagedAndGrabberFollowsM7) {
  frames::M7 m7;
  m7.kick = frames::M7::make_kick(true, 30);
  m7.grabber_mode = 70;
  run_.run_until(20ms);
  laptop_.send(set_->m7.encode(m7));
  run_.run_until(25ms);
  EXPECT_EQ(robot_.kicks, 0) << "not engaged: no kick";
  EXPECT_EQ(robot_.grabber, 70);
  robot_.engaged = true;
  laptop_.send(set_->m7.encode(m7));
  run_.run_until(70ms);
  EXPECT_EQ(robot_.kicks, 1);
  const auto m9 = laptop_.with_id(0x151);
  frames::M9 last;
  ASSERT_TRUE(set_->m9.decode(m9.back().frame, last).ok());
  EXPECT_EQ(last.just_kicked, 1);
  EXPECT_EQ(last.ball_engaged, 1);
  EXPECT_EQ(last.grabber, 70);
  run_.run_until(400ms);
  ASSERT_TRUE(set_->m9.decode(laptop_.with_id(0x151).back().frame, last).ok());
  EXPECT_EQ(last.just_kicked, 0) << "reset after the hold time";
}

TEST_F(NodesTest, MalformedFramesAreCountedAndChangeNothing) {
  laptop_.m6_1 = frames::M6_1{0, 0.5};
  run_.run_until(500ms);
  const int before = nodes_.pic_base().setpoints()[0];
  laptop_.m6_1.reset();  // only the malformed frames below reach Pic_base now... and the watchdog stays off
  frames::CanFrame short_m6 = set_->m6_1.encode(frames::M6_1{0, 3.0});
  short_m6.len = 4;
  frames::CanFrame bad_m1 = set_->m1.encode(frames::M1{});
  bad_m1.data[0] = 0xE8;  // setpoint_1 = 1000 > 900
  bad_m1.data[1] = 0x03;
  for (int i = 0; i < 5; ++i) {
    laptop_.send(short_m6);
    laptop_.send(bad_m1);
    laptop_.send(frames::make_data_frame(0x7FF, {1, 2, 3}));
    run_.run_for(10ms);
  }
  // Exactly these, and no other error counter (the fixture checks at the end).
  counters.expect("Pic_base.wrong_length", 5);
  for (const char* motor : {"Motor1", "Motor2", "Motor3"}) {
    counters.expect(std::string(motor) + ".out_of_range", 5);  // each motor consumes M1
  }
  counters.expect("SysMon.unknown_id", 5);
  EXPECT_EQ(nodes_.pic_base().setpoints()[0], before) << "the short M6 changed nothing";
  EXPECT_NEAR(robot_.speed[0], params_.encoder.wheel_radps(before), 1e-9) << "the bad M1 changed nothing";
  run_.run_for(1s);
  const auto m10 = laptop_.decoded(set_->m10);
  ASSERT_FALSE(m10.empty());
  EXPECT_EQ(m10.back().errors, 5 + 15 + 5) << "M10 reports every bad frame the nodes counted";
}

TEST_F(NodesTest, SystemMonitorReportsWhoIsAliveAndASwitchedOffNode) {
  laptop_.m6_1 = frames::M6_1{0, 0.2};
  run_.run_until(1050ms);
  auto m10 = laptop_.decoded(set_->m10);
  ASSERT_FALSE(m10.empty());
  EXPECT_EQ(m10.back().alive, 0x3F) << "all six nodes seen";
  EXPECT_EQ(m10.back().node_state, 0);
  nodes_.node(NodeId::kCompass).set_enabled(false);
  run_.run_until(2050ms);
  m10 = laptop_.decoded(set_->m10);
  EXPECT_EQ(m10.back().alive, 0x3F & ~0x20) << "the compass is silent";
  EXPECT_EQ(m10.back().node_state & 2, 2);
  EXPECT_TRUE(laptop_.with_id(0x141).back().time < 1060ms) << "no M8 after switching it off";
}

TEST_F(NodesTest, FaultHookDropsDelaysCorruptsAndDuplicates) {
  struct Hook final : FaultHook {
    FaultDecision on_send(const std::string& node, const frames::CanFrame& f, Nanos) override {
      FaultDecision d;
      if (node == "Compass") d.drop = true;
      if (node == "Motor2") d.delay = 1ms;
      if (node == "Motor3") d.duplicates = 1;
      if (node == "Motor1" && f.id == 0x111) {
        d.corrupt_byte = 7;
        d.corrupt_mask = 0x80;
      }
      return d;
    }
  } hook;
  nodes_.set_fault_hook(&hook);
  run_.run_until(100ms - 1ns);  // ECs 0..9; EC 9's delayed M3_2 falls after the cut
  EXPECT_TRUE(laptop_.with_id(0x141).empty()) << "dropped";
  counters.expect("Compass.fault_dropped", 2);
  const auto m3_2 = laptop_.with_id(0x112);
  ASSERT_EQ(m3_2.size(), 9u);
  for (std::size_t k = 0; k < m3_2.size(); ++k) EXPECT_EQ(m3_2[k].time, window_start(k) + 1ms) << "delayed, EC " << k;
  EXPECT_EQ(laptop_.with_id(0x113).size(), 20u) << "duplicated";
  frames::M3 m3;
  ASSERT_TRUE(set_->m3[0].decode(laptop_.with_id(0x111)[0].frame, m3).ok());
  EXPECT_EQ(m3.seq, 0x80) << "seq byte corrupted";
}

// The master alone on a memory bus at a bit rate whose bit is 1.25 us: the
// window each TM announces is the schedule's rounded up to a microsecond, never
// shorter than the frames due need (truncating it did, by up to 1 us).
TEST(FttMasterWindow, TheAnnouncedWindowIsTheSchedulesRoundedUp) {
  const auto set = frames::MessageSet::load(test::shipped_dbc());
  frames::FttConfig config;
  config.bit_rate = 800'000;
  const frames::FttSchedule schedule(*set, config);
  SimulatedClock clock;
  MemoryBus bus(clock);
  const auto endpoint = bus.attach("master");
  FttMaster master(*endpoint, set, schedule, Nanos{0});
  test::LaptopEndpoint laptop(bus, set, config.elementary_cycle);
  VirtualTime run(clock);
  run.add(master);
  run.add(laptop);
  run.run_until(295ms);
  const auto tms = laptop.decoded(set->tm);
  ASSERT_EQ(tms.size(), 30u);
  int fractional = 0;
  for (std::size_t k = 0; k < tms.size(); ++k) {
    const Nanos needed = schedule.sync_window(tms[k].sync_bitmap);
    const Nanos announced = std::chrono::microseconds(tms[k].sync_window_us);
    EXPECT_GE(announced, needed) << "EC " << k;
    EXPECT_LT(announced - needed, 1us) << "EC " << k;
    fractional += needed % 1us != Nanos{0} ? 1 : 0;
  }
  EXPECT_GT(fractional, 0) << "at 800 kbit/s some windows are not whole microseconds";
}

// A window the TM's 16-bit field cannot carry is refused with what to do,
// never sent wrapped round.
TEST(FttMasterWindow, AWindowLongerThanTheFieldCanSayIsRefused) {
  const auto set = frames::MessageSet::load(test::shipped_dbc());
  frames::FttConfig config;
  config.elementary_cycle = 200ms;
  const std::vector<frames::FttEntry> entries = {
      {"TM", frames::FttKind::kTrigger, -1, 200ms, 100us},
      {"SLOW", frames::FttKind::kSync, 0, 200ms, 70ms},
  };
  const frames::FttSchedule schedule(entries, config);
  ASSERT_TRUE(schedule.fits());
  SimulatedClock clock;
  MemoryBus bus(clock);
  const auto endpoint = bus.attach("master");
  try {
    FttMaster master(*endpoint, set, schedule, Nanos{0});
    ADD_FAILURE() << "a 70 ms window was accepted";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("is 70020 us, more than the trigger message's sync_window_us can say"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("raise the bit rate"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canhil::can_nodes
