// The closed loop over a real vcan: `canhil nodes` (the emulator) in its own
// process, this test on its own socket playing the laptop. Runs through
// vcan_setup/with-vcan.sh (inside the VM runner where the kernel has no CAN).
// Real time on a shared or emulated machine is noisy: this checks order,
// counts and outcomes, never timing.
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/closed_loop_test.cpp).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <optional>
#include <string>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/frames/messages.hpp"
#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace canhil {
namespace {

using namespace std::chrono_literals;

struct Emulator {
  explicit Emulator(const std::string& args)
      : process(test::canhil_binary() + " nodes --iface vcan0 --quiet " + args, "/tmp/canhil_vcan_closed_loop.log") {}
  int stop() { return process.stop(); }
  std::string output() const { return process.output(); }
  test::ChildProcess process;
};

class HandlerStandIn {
 public:
  HandlerStandIn()
      : set_(frames::MessageSet::load(test::shipped_dbc())), bus_(can_nodes::SocketCanBus::open("vcan0")) {}

  /// Handles frames for `duration` of wall time; sends M6 in reply to each TM
  /// that schedules it while `drive` is set. Returns TMs seen.
  int run(Nanos duration) {
    const can_nodes::WallClock clock;
    const Nanos end = clock.now() + duration;
    int tms = 0;
    while (clock.now() < end) {
      if (!bus_->wait_readable(20ms)) continue;
      while (auto f = bus_->receive()) {
        frames::Tm tm;
        frames::M4_1 m4;
        if (frames::is_message(f->frame, set_->tm.message()) && set_->tm.decode(f->frame, tm).ok()) {
          ++tms;
          if (drive && (tm.sync_bitmap & (1u << 6)) != 0) {
            bus_->send(set_->m6_1.encode(*drive));
            bus_->send(set_->m6_2.encode(frames::M6_2{}));
          }
        } else if (frames::is_message(f->frame, set_->m4_1.message()) && set_->m4_1.decode(f->frame, m4).ok()) {
          last_m4 = m4;
          ++m4_count;
        }
      }
    }
    return tms;
  }
  void send(const frames::CanFrame& f) { bus_->send(f); }

  std::optional<frames::M6_1> drive;
  std::optional<frames::M4_1> last_m4;
  int m4_count = 0;
  std::shared_ptr<const frames::MessageSet> set_;

 private:
  std::unique_ptr<can_nodes::SocketCanBus> bus_;
};

TEST(VcanClosedLoop, HandlerOnASeparateProcessDrivesTheEmulatedRobot) {
  Emulator emu("--duration 60");
  HandlerStandIn handler;
  // Wait (at most 30 s: sanitizer builds under the VM's emulation start slowly)
  // until the emulator's FTT master is running.
  int tms = 0;
  for (int i = 0; i < 30 && tms < 20; ++i) tms += handler.run(1s);
  ASSERT_GE(tms, 20) << "the emulator's FTT master is running\n" << emu.output();
  handler.send(handler.set_->m5_1.encode(frames::M5_1{0, 0}));
  handler.send(handler.set_->m5_2.encode(frames::M5_2{0, frames::M5_2::kReset}));
  handler.drive = frames::M6_1{0, 0.5};
  EXPECT_GT(handler.run(2s), 50);
  handler.drive.reset();
  handler.run(800ms);  // watchdog brake, then fresh M4
  ASSERT_TRUE(handler.last_m4.has_value());
  // Real time on an emulated machine: check the outcome, not the exact distance
  // (virtual-time tests check that: 1.0 m +- 0.1).
  EXPECT_GT(handler.last_m4->y, 0.5) << "driven forward by the M6 this test sent";
  EXPECT_LT(handler.last_m4->y, 1.5);
  EXPECT_NEAR(handler.last_m4->x, 0.0, 0.15);
  handler.send(handler.set_->m5_1.encode(frames::M5_1{0, 0}));
  handler.send(handler.set_->m5_2.encode(frames::M5_2{0, frames::M5_2::kReset}));
  // The reset is sporadic and M4 comes every 100 ms: wait (at most 10 s, the
  // VM may be slow) for an M4 sent after the reset took effect.
  for (int i = 0; i < 100 && std::abs(handler.last_m4->y) > 0.01; ++i) handler.run(100ms);
  EXPECT_NEAR(handler.last_m4->y, 0.0, 0.01) << "M5 reset";
  emu.stop();
  const std::string out = emu.output();
  EXPECT_NE(out.find("summary after"), std::string::npos) << out;
  EXPECT_NE(out.find("Pic_base"), std::string::npos) << out;
}

}  // namespace
}  // namespace canhil
