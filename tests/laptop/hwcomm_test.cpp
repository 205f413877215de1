// The reference handler alone: HwComm fed frames by hand, with its own RTDB
// and a clock the test sets. What it writes for each frame, what it sends in
// which slot, and what it counts. (In the loop with the emulated nodes:
// tests/emulator/handler_participant_test.cpp.)
// Silent trouble (test::WatchedTest): no node runs here; the handler's own
// counts are what these tests check, each by name.
#include "canhil/laptop/hwcomm.hpp"

#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"
#include "support/rtdb_ipc.hpp"
#include "support/team_rtdb.hpp"
#include "support/test_paths.hpp"

namespace canhil::laptop {
namespace {

using namespace std::chrono_literals;

class HwCommUnit : public ::testing::Test {
 protected:
  HwCommUnit() {
    setenv("AGENT", "1", 1);
    EXPECT_EQ(DB_init(), 0);
    db_ = rtdb::open_builtin(rtdb::Scope::kOneAgent);
    hw_ = std::make_unique<HwComm>(
        set_, 10ms,
        [this](const frames::CanFrame& f) {
          sent_.push_back(f);
          return true;
        },
        [this] { return now_; }, *db_, layout_, CAMBADA_1);
  }
  ~HwCommUnit() override {
    hw_.reset();
    db_.reset();
    DB_free();
  }

  // A TM of EC `ec` at `t`, scheduling `bitmap`, with a 1 ms synchronous window.
  void tm(std::uint16_t ec, Nanos t, std::uint32_t bitmap) {
    now_ = t;
    hw_->on_frame(set_->tm.encode(frames::Tm{ec, bitmap, 1000}), t);
  }
  // The last TM's asynchronous window opens: the TM (8 bytes, at most 135 bits
  // at 1 Mbit/s) has left the wire.
  void window_opens() {
    now_ += kTmWire;
    hw_->on_time(now_);
  }
  static constexpr Nanos kTmWire = 135us;
  std::uint32_t bit(const char* name) const { return 1u << set_->ftt(*set_->codec().find(name)).index; }
  std::vector<frames::CanFrame> sent_with(std::uint32_t id) const {
    std::vector<frames::CanFrame> out;
    for (const auto& f : sent_) {
      if (f.id == id) out.push_back(f);
    }
    return out;
  }

  test::RtdbKeys keys_;  // keys of its own, set (as a member) before the constructor calls DB_init
  std::shared_ptr<const frames::MessageSet> set_ = frames::MessageSet::load(test::shipped_dbc());
  std::vector<frames::CanFrame> sent_;
  Nanos now_{0};
  std::unique_ptr<rtdb::Database> db_;
  const rtdb::Layout layout_ = rtdb::Layout::shipped("canhil");
  std::unique_ptr<HwComm> hw_;
};

TEST_F(HwCommUnit, SendsCmdVelInTheM6SlotOfTheTmThatSchedulesIt) {
  CMD_Vel v{0.25f, -0.5f, 1.5f, true};
  DB_put(CMD_VEL, &v);
  tm(1, 10ms, bit("M3_1"));
  EXPECT_EQ(hw_->next_deadline(), 10ms + kTmWire) << "the asynchronous window's opening: the TM off the wire";
  window_opens();
  EXPECT_EQ(hw_->next_deadline(), kNever) << "M6 not due in this EC";
  tm(3, 30ms, bit("M6_1") | bit("M6_2"));
  window_opens();
  EXPECT_EQ(hw_->next_deadline(), 30ms + 10ms - 1ms) << "the window's start: TM + EC - window";
  now_ = 39ms - 1ns;
  hw_->on_time(now_);
  EXPECT_TRUE(sent_with(set_->m6_1.message().id()).empty()) << "not before the slot";
  EXPECT_EQ(sent_with(set_->m7.message().id()).size(), 1u)
      << "the grabber's first state, once, in the first asynchronous window";
  now_ = 39ms;
  hw_->on_time(now_);
  const auto m6_1s = sent_with(set_->m6_1.message().id());
  const auto m6_2s = sent_with(set_->m6_2.message().id());
  ASSERT_EQ(m6_1s.size(), 1u);
  ASSERT_EQ(m6_2s.size(), 1u);
  frames::M6_1 m6_1;
  frames::M6_2 m6_2;
  ASSERT_TRUE(set_->m6_1.decode(m6_1s[0], m6_1).ok());
  ASSERT_TRUE(set_->m6_2.decode(m6_2s[0], m6_2).ok());
  EXPECT_DOUBLE_EQ(m6_1.vx, 0.25);
  EXPECT_DOUBLE_EQ(m6_1.vy, -0.5);
  EXPECT_DOUBLE_EQ(m6_2.va, 1.5);
  EXPECT_EQ(m6_2.small_adjustment, 1);
  EXPECT_EQ(hw_->next_deadline(), kNever);
  EXPECT_EQ(hw_->sent("M6_1"), 1u);
  EXPECT_EQ(hw_->received("TM"), 2u);
}

TEST_F(HwCommUnit, ItsControllersErrorFramesAreCountedWithItsStateAndCounters) {
  // As can-dev reports them (linux/can/error.h): a bus error with the
  // counters, a change to error-passive, bus-off, the restart.
  frames::CanFrame e;
  e.kind = frames::FrameKind::kError;
  e.len = 8;
  e.id = frames::kErrorClassProtocol | frames::kErrorClassBusError | frames::kErrorClassCounters;
  e.data[6] = 8;
  hw_->on_frame(e, 1ms);
  EXPECT_EQ(hw_->stats().bus_errors, 1u);
  EXPECT_EQ(hw_->stats().tec, 8);
  EXPECT_EQ(hw_->stats().controller, ControllerState::kErrorActive);
  e.id = frames::kErrorClassController | frames::kErrorClassCounters;
  e.data[1] = frames::kControllerTxPassive;
  e.data[6] = 128;
  hw_->on_frame(e, 2ms);
  EXPECT_EQ(hw_->stats().controller, ControllerState::kErrorPassive);
  EXPECT_EQ(hw_->stats().tec, 128);
  e.id = frames::kErrorClassBusOff;
  hw_->on_frame(e, 3ms);
  EXPECT_EQ(hw_->stats().controller, ControllerState::kBusOff);
  e.id = frames::kErrorClassRestarted | frames::kErrorClassCounters;
  e.data[6] = 0;
  hw_->on_frame(e, 4ms);
  EXPECT_EQ(hw_->stats().controller, ControllerState::kErrorActive);
  EXPECT_EQ(hw_->stats().error_frames, 4u);
  EXPECT_EQ(hw_->stats().bus_offs, 1u);
  EXPECT_EQ(hw_->stats().restarts, 1u);
  EXPECT_EQ(hw_->stats().unknown_id, 0u) << "an error frame is no message";
  EXPECT_NE(hw_->summary().find("1 bus-off, 1 restarts), controller error-active"), std::string::npos)
      << hw_->summary();
}

TEST_F(HwCommUnit, OdometryBecomesCmdPosWithTheChangeSinceTheLast) {
  hw_->on_frame(set_->m4_2.encode(frames::M4_2{0.5, 0}), 0ms);
  CMD_Pos p{};
  DB_get(Whoami(), CMD_POS, &p);
  EXPECT_EQ(p.pa, 0.0f) << "an M4_2 without its M4_1 is not a pose";
  hw_->on_frame(set_->m4_1.encode(frames::M4_1{1.0, 2.0}), 50ms);
  hw_->on_frame(set_->m4_2.encode(frames::M4_2{0.5, 1}), 50ms);
  DB_get(Whoami(), CMD_POS, &p);
  EXPECT_FLOAT_EQ(p.px, 1.0f);
  EXPECT_FLOAT_EQ(p.py, 2.0f);
  EXPECT_FLOAT_EQ(p.pa, 0.5f);
  EXPECT_EQ(p.dx, 0.0f) << "the first pose has no change";
  hw_->on_frame(set_->m4_1.encode(frames::M4_1{1.25, 1.5}), 100ms);
  hw_->on_frame(set_->m4_2.encode(frames::M4_2{-3.0, 2}), 100ms);
  DB_get(Whoami(), CMD_POS, &p);
  EXPECT_NEAR(p.dx, 0.25, 1e-6);
  EXPECT_NEAR(p.dy, -0.5, 1e-6);
  EXPECT_NEAR(p.da, -3.0 - 0.5 + 2 * M_PI, 1e-5) << "the heading change wrapped to (-pi, pi]";
}

TEST_F(HwCommUnit, AKickGoesOutOnceInTheAsynchronousWindowAndItsPowerIsReset) {
  CMD_Kicker k{static_cast<unsigned char>(0x80 | 30), 70, 35};
  DB_put(CMD_KICKER, &k);
  tm(0, 0ms, 0);
  EXPECT_TRUE(sent_with(set_->m7.message().id()).empty()) << "not while the TM is on the wire";
  window_opens();
  const auto m7 = sent_with(set_->m7.message().id());
  ASSERT_EQ(m7.size(), 1u) << "when the TM has left the wire, opening the asynchronous window";
  frames::M7 decoded;
  ASSERT_TRUE(set_->m7.decode(m7[0], decoded).ok());
  EXPECT_EQ(decoded.kick, 0x80 | 30);
  EXPECT_EQ(decoded.eng_lvl_high, 70);
  CMD_Kicker after{};
  DB_get(Whoami(), CMD_KICKER, &after);
  EXPECT_EQ(after.power, 0) << "sent once: the agent asks again for another kick";
  DB_put(CMD_KICKER, &k);
  tm(1, 990ms, 0);
  window_opens();
  EXPECT_EQ(sent_with(set_->m7.message().id()).size(), 1u) << "not within M7's minimum gap (1000 ms)";
  tm(2, 1000ms, 0);
  window_opens();
  EXPECT_EQ(sent_with(set_->m7.message().id()).size(), 2u) << "at the gap";
  EXPECT_EQ(hw_->stats().kicks_sent, 2u);
}

TEST_F(HwCommUnit, BadTrafficIsCountedAndWritesNothing) {
  frames::CanFrame short_m8 = set_->m8.encode(frames::M8{90, 0});
  short_m8.len = 4;
  hw_->on_frame(short_m8, 0ms);
  hw_->on_frame(frames::make_data_frame(0x7FF, {1, 2}), 0ms);
  CMD_Imu imu{};
  DB_get(Whoami(), CMD_IMU, &imu);
  EXPECT_EQ(imu.yaw, 0);
  tm(10, 0ms, 0);
  tm(13, 30ms, 0);  // ECs 11 and 12 were never heard
  EXPECT_EQ(hw_->stats().wrong_length, 1u);
  EXPECT_EQ(hw_->stats().unknown_id, 1u);
  EXPECT_EQ(hw_->stats().missed_tms, 2u);
  EXPECT_NE(hw_->summary().find("missed TMs 2, wrong length 1"), std::string::npos) << hw_->summary();
  EXPECT_NE(hw_->summary().find("received: M8 1 TM 2"), std::string::npos) << hw_->summary();
}

// The same handler serving a CAMBADA-like team: the stand-in team library
// (CAMBADA's API, its own keys) with a CAMBADA-like table, in CAMBADA's
// layout. In an IPC namespace of its own.
class HwCommCambada : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(unshare(CLONE_NEWIPC), 0) << "a private IPC namespace needs root (CAP_SYS_ADMIN): " << strerror(errno);
    setenv("AGENT", "1", 1);
    const std::string dir = test::source_dir() + "/tests/support/cambada_like/";
    db_ = rtdb::open_library(test::team_rtdb_library(),
                             rtdb::ItemTable::from_files(dir + "rtdb_user.h", dir + "config/rtdb.ini"),
                             rtdb::Scope::kOneAgent, dir + "config/rtdb.ini");
    hw_ = std::make_unique<HwComm>(
        set_, 10ms,
        [this](const frames::CanFrame& f) {
          sent_.push_back(f);
          return true;
        },
        [this] { return now_; }, *db_, layout_, 1);
  }
  int id(const char* item) const { return *db_->items().id(item); }
  std::vector<std::byte> get(const char* item) {
    std::vector<std::byte> b(*db_->items().size(id(item)));
    EXPECT_TRUE(db_->get(1, 1, id(item), b).has_value());
    return b;
  }
  template <class T>
  T at(const std::vector<std::byte>& b, std::size_t offset) {
    T v{};
    std::memcpy(&v, b.data() + offset, sizeof v);
    return v;
  }
  template <class T, std::size_t N>
  void put(const char* item, const std::array<T, N>& fields) {
    std::vector<std::byte> b(*db_->items().size(id(item)));
    std::memcpy(b.data(), fields.data(), std::min(b.size(), sizeof(T) * N));
    db_->put(1, 1, id(item), b);
  }
  std::uint32_t bit(const char* name) const { return 1u << set_->ftt(*set_->codec().find(name)).index; }

  std::shared_ptr<const frames::MessageSet> set_ = frames::MessageSet::load(test::shipped_dbc());
  const rtdb::Layout layout_ = rtdb::Layout::shipped("cambada");
  std::unique_ptr<rtdb::Database> db_;
  std::vector<frames::CanFrame> sent_;
  Nanos now_{0};
  std::unique_ptr<HwComm> hw_;
};

TEST_F(HwCommCambada, OdometryDeltasInTheRobotsFrameInMillimetres) {
  const double quarter = M_PI / 2;  // the robot's +x axis along the field's +y
  hw_->on_frame(set_->m4_1.encode(frames::M4_1{1.0, 2.0}), 10ms);
  hw_->on_frame(set_->m4_2.encode(frames::M4_2{quarter, 1}), 10ms);
  hw_->on_frame(set_->m4_1.encode(frames::M4_1{1.0, 2.1}), 20ms);
  hw_->on_frame(set_->m4_2.encode(frames::M4_2{quarter, 2}), 20ms);
  const auto p = get("CMD_POS");
  EXPECT_FLOAT_EQ(at<float>(p, 4), 2.1F) << "py in metres";
  EXPECT_NEAR(at<float>(p, 12), 100.0F, 1e-3) << "0.1 m along +y is 100 mm along the robot's +x";
  EXPECT_NEAR(at<float>(p, 16), 0.0F, 1e-3);
}

TEST_F(HwCommCambada, VoltagesInTenthsCompassWithTheNorthAndArmsForTheBarrier) {
  hw_->on_frame(set_->m2.encode(frames::M2{12.5, 12.4, 25.0, 0}), 10ms);
  hw_->on_frame(set_->m9.encode(frames::M9{1, 0, 180.0, 100}), 10ms);
  hw_->on_frame(set_->m8.encode(frames::M8{90.0, 7}), 10ms);
  const auto info = get("CMD_INFO");
  EXPECT_EQ(at<std::uint16_t>(info, 0), 125) << "Voltage_logic in 0.1 V";
  EXPECT_EQ(at<std::uint16_t>(info, 4), 250);
  EXPECT_EQ(at<std::uint16_t>(info, 6), 1800) << "Kicker_voltage";
  const auto arms = get("CMD_GRABBER_INFO");
  EXPECT_EQ(at<std::uint32_t>(arms, 0), 100u) << "ball engaged: arms closed (> 70)";
  // 90 degrees clockwise from north is -90 counter-clockwise, plus theNorth -80.
  EXPECT_EQ(at<std::int32_t>(get("CMD_IMU"), 0), -170);
}

TEST_F(HwCommCambada, EchoesLastCmdVelMapsTheGrabberAndResetsTheKick) {
  put("CMD_VEL", std::array<float, 3>{0.25F, 1.5F, -0.5F});
  put("CMD_GRABBER", std::array<std::uint8_t, 1>{1});
  put("CMD_KICKER", std::array<std::uint8_t, 3>{50, 70, 35});
  now_ = 30ms;
  hw_->on_frame(set_->tm.encode(frames::Tm{3, bit("M6_1") | bit("M6_2"), 1000}), now_);
  now_ = 39ms;
  hw_->on_time(now_);
  const auto last = get("LAST_CMD_VEL");
  EXPECT_FLOAT_EQ(at<float>(last, 0), 0.25F) << "the handler's echo of what it sent";
  EXPECT_FLOAT_EQ(at<float>(last, 4), 1.5F);
  EXPECT_FLOAT_EQ(at<float>(last, 8), -0.5F);
  std::vector<frames::M7> m7s;
  for (const auto& f : sent_) {
    frames::M7 m7;
    if (f.id == set_->m7.message().id() && set_->m7.decode(f, m7).ok()) m7s.push_back(m7);
  }
  ASSERT_EQ(m7s.size(), 1u);
  EXPECT_EQ(m7s[0].kick, 50);
  EXPECT_EQ(m7s[0].grabber_mode, 100) << "CAMBADA's grabber 1 is on: 100";
  EXPECT_EQ(m7s[0].eng_lvl_high, 70);
  EXPECT_EQ(m7s[0].eng_lvl_low, 35);
  const auto kicker = get("CMD_KICKER");
  EXPECT_EQ(at<std::uint8_t>(kicker, 0), 0) << "sent once: the kick reset";
  EXPECT_EQ(at<std::uint8_t>(kicker, 1), 70) << "the thresholds kept";
}

}  // namespace
}  // namespace canhil::laptop
