// The reference handler in the loop, in virtual time: HwComm as the virtual
// driver runs it (HandlerParticipant) on the memory bus, against the emulated
// nodes and the physics, with a real RTDB. (HwComm alone: tests/laptop.)
#include "canhil/emulator/handler_participant.hpp"

#include <gtest/gtest.h>
#include <sys/shm.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"
#include "support/counter_watch.hpp"
#include "support/one_robot_session.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

// HwComm as a participant of the lockstep runner, on a memory endpoint. No
// node and no handler counts a bad frame, a missed TM or a failed send unless
// a test says so.
class HwCommTest : public test::WatchedTest {
 protected:
  HwCommTest() {
    setenv("RTDB_KEY", std::to_string(0x5B000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    setenv("AGENT", "1", 1);
    EXPECT_EQ(DB_init(), 0);
    set_ = frames::MessageSet::load(test::shipped_dbc());
    physics::WorldParams wp;
    wp.robots = {physics::Placement{0, 0, 0}};
    wp.ball_start = {0, 0.26, wp.ball.radius_m};  // in the mouth
    robot_ = std::make_unique<test::OneRobotSession>(set_, wp);
    db_ = rtdb::open_builtin(rtdb::Scope::kOneAgent);
    laptop_ = std::make_unique<HandlerParticipant>(robot_->bus(), set_, 10ms, robot_->clock(), *db_, layout_, CAMBADA_1,
                                                   true);
    robot_->add(*laptop_);
    counters.watch_nodes(robot_->nodes());
    const laptop::HwCommStats& hw = laptop_->hw().stats();
    counters.watch("handler.wrong_length", [&hw] { return hw.wrong_length; });
    counters.watch("handler.out_of_range", [&hw] { return hw.out_of_range; });
    counters.watch("handler.unknown_id", [&hw] { return hw.unknown_id; });
    counters.watch("handler.missed_tms", [&hw] { return hw.missed_tms; });
    counters.watch("handler.send_failed", [&hw] { return hw.send_failed; });
  }
  ~HwCommTest() override {
    laptop_.reset();
    db_.reset();
    DB_free();
  }
  int count_sent(std::uint32_t id) const {
    int n = 0;
    for (const auto& f : laptop_->sent()) n += f.id == id ? 1 : 0;
    return n;
  }

  std::shared_ptr<const frames::MessageSet> set_;
  std::unique_ptr<test::OneRobotSession> robot_;
  std::unique_ptr<rtdb::Database> db_;
  const rtdb::Layout layout_ = rtdb::Layout::shipped("canhil");
  std::unique_ptr<HandlerParticipant> laptop_;
};

TEST_F(HwCommTest, CmdVelMovesCmdPos) {
  CMD_Vel v{0, 0.5f, 0, false};
  DB_put(CMD_VEL, &v);
  robot_->run_until(2s);
  CMD_Vel stop{0, 0, 0, false};
  DB_put(CMD_VEL, &stop);
  robot_->run_for(600ms);
  CMD_Pos p{};
  const int age = DB_get(CAMBADA_1, CMD_POS, &p);
  EXPECT_GE(age, 0);
  EXPECT_NEAR(p.py, 1.0, 0.1);
  EXPECT_NEAR(p.px, 0.0, 0.02);
  EXPECT_EQ(count_sent(0x131), count_sent(0x132));
  EXPECT_GE(count_sent(0x131), 85) << "M6 in every third EC: about 87 in 2.6 s";
  EXPECT_EQ(robot_->nodes().bad_frames(), 0u);
}

TEST_F(HwCommTest, KickerCommandIsSentExactlyOnceAndReset) {
  CMD_Grabber g{100};
  DB_put(CMD_GRABBER, &g);
  robot_->run_until(1200ms);  // the grabber M7 went out; its minimum gap has passed
  const int m7_before = count_sent(0x0B0);
  EXPECT_EQ(m7_before, 1) << "one M7 for the grabber change";
  CMD_Grabber_Info gi{};
  DB_get(CAMBADA_1, CMD_GRABBER_INFO, &gi);
  ASSERT_EQ(gi.ballEngaged, 1);
  CMD_Kicker k{static_cast<unsigned char>(0x80 | 40), 0, 0};
  DB_put(CMD_KICKER, &k);
  robot_->run_for(3s);
  EXPECT_EQ(count_sent(0x0B0), m7_before + 1) << "exactly one M7 for the kick";
  EXPECT_EQ(laptop_->hw().stats().kicks_sent, 1u);
  CMD_Kicker after{};
  DB_get(CAMBADA_1, CMD_KICKER, &after);
  EXPECT_EQ(after.power, 0) << "power reset once sent";
  EXPECT_GT(robot_->world().ball_position().y(), 2.0) << "the ball was kicked";
}

TEST_F(HwCommTest, BusToRtdbItemsAreWritten) {
  CMD_Vel v{0, 0.3f, 0.2f, false};
  DB_put(CMD_VEL, &v);
  robot_->run_until(1500ms);
  CMD_Info info{};
  EXPECT_GE(DB_get(CAMBADA_1, CMD_INFO, &info), 0);
  EXPECT_NEAR(info.Voltage_power24 / 100.0, 25.0, 1.0);
  EXPECT_NEAR(info.Kicker_voltage / 100.0, 180.0, 1.0);
  CMD_Imu imu{};
  DB_get(CAMBADA_1, CMD_IMU, &imu);
  const double heading = robot_->world().robot(0).compass_heading_deg();
  EXPECT_NEAR(imu.yaw / 100.0, heading, 2.0);
  CMD_HWerrors e{};
  DB_get(CAMBADA_1, CMD_HWERRORS, &e);
  EXPECT_EQ(e.error_count[0][1], 0x3F) << "all nodes alive, from M10";
  EXPECT_EQ(e.error_count[0][0], 0) << "no bad frames";
  EXPECT_FALSE(laptop_->hw().stats().latencies.empty());
}

TEST_F(HwCommTest, SetPoseAndResetThroughM5) {
  CMD_SetPose sp{1.5f, -2.0f, 0.75f, 0, 1};
  DB_put(CMD_SETPOSE, &sp);
  robot_->run_until(300ms);
  CMD_Pos p{};
  DB_get(CAMBADA_1, CMD_POS, &p);
  EXPECT_NEAR(p.px, 1.5, 1e-3);
  EXPECT_NEAR(p.py, -2.0, 1e-3);
  EXPECT_NEAR(p.pa, 0.75, 1e-4);
  CMD_SetPose after{};
  DB_get(CAMBADA_1, CMD_SETPOSE, &after);
  EXPECT_EQ(after.pending, 0);
  EXPECT_EQ(count_sent(0x0A1), 1);
  EXPECT_EQ(count_sent(0x0A2), 1);
}

TEST_F(HwCommTest, FaultRulesNamingTheLaptopReachWhatItSends) {
  // A slow laptop (docs/faults.md): its M6_1 10 ms late, the set-pose's M5_1
  // lost; the handler believes both sent, the bus carries them late or not.
  can_nodes::FaultInjector faults({can_nodes::parse_fault("delay:M6_1:10"), can_nodes::parse_fault("drop:M5_1")}, set_,
                                  {"Pic_base"}, 1);
  laptop_->set_fault_hook(&faults);
  auto listener = robot_->bus().attach("listener", 1 << 16);
  CMD_Vel v{0, 0.5f, 0, false};
  DB_put(CMD_VEL, &v);
  CMD_SetPose sp{1.5f, -2.0f, 0.75f, 0, 1};
  DB_put(CMD_SETPOSE, &sp);
  robot_->run_until(1s);
  Nanos last_m6_2{-1};
  int late = 0, m6_1 = 0, m5_1 = 0;
  while (auto f = listener->receive()) {
    if (f->frame.id == 0x132) last_m6_2 = f->time;
    if (f->frame.id == 0x0A1) ++m5_1;
    if (f->frame.id != 0x131) continue;
    ++m6_1;
    late += f->time - last_m6_2 >= 10ms ? 1 : 0;  // its M6_2, sent with it, went 10 ms before
  }
  EXPECT_GT(m6_1, 25);
  EXPECT_EQ(late, m6_1) << "every M6_1 one EC after its M6_2";
  EXPECT_EQ(m5_1, 0);
  EXPECT_EQ(count_sent(0x0A2), 1);
  const auto counts = faults.counts();
  EXPECT_EQ(count_sent(0x131), m6_1) << "what reached the bus";
  EXPECT_LE(counts[0].applied - static_cast<std::uint64_t>(m6_1), 1U) << "the last one may still wait its 10 ms";
  EXPECT_EQ(counts[1].applied, 1U);
  CMD_Pos p{};
  DB_get(CAMBADA_1, CMD_POS, &p);
  EXPECT_GT(std::abs(p.px - 1.5), 0.5) << "the odometry never set: M5_1 lost";
}

}  // namespace
}  // namespace canhil::emulator
