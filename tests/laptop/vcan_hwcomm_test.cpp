// The reference handler against the emulated nodes over a real vcan:
// `canhil nodes` (emulator), `canhil-hwcomm` (handler) and rtdb_drive (a C
// program linked only against the RTDB library) are separate processes; this
// test watches the bus. Runs through vcan_setup/with-vcan.sh.
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/handler_participant_test.cpp).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <string>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "support/child_process.hpp"
#include "support/rtdb_ipc.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p) != nullptr) out += buf;
  pclose(p);
  return out;
}

TEST(VcanHwcomm, HandlerBetweenTheEmulatedNodesAndTheRtdb) {
  const canhil::test::RtdbKeys keys;  // its own keys: never another test's (0x5C + pid << 8 could meet HwCommUnit's)
  setenv("AGENT", "1", 1);
  const std::string bin = canhil::test::build_dir();
  canhil::test::ChildProcess emulator(bin + "/app/canhil nodes --iface vcan0 --quiet",
                                      "/tmp/canhil_vcan_hwcomm_nodes.log");
  canhil::test::ChildProcess handler(bin + "/laptop/canhil-hwcomm --iface vcan0",
                                     "/tmp/canhil_vcan_hwcomm_handler.log");
  // Count M7 on the bus from here.
  auto bus = canhil::can_nodes::SocketCanBus::open("vcan0");
  const canhil::can_nodes::Filter m7[] = {canhil::can_nodes::Filter::exact(0x0B0)};
  bus->set_filters(m7);
  std::atomic<bool> done{false};
  std::atomic<int> m7_seen{0};
  std::thread counter([&] {
    while (!done) {
      if (bus->wait_readable(50ms)) {
        while (bus->receive()) ++m7_seen;
      }
    }
  });
  // Wait (at most 30 s: sanitizer builds under the VM's emulation start slowly)
  // until the handler has written CMD_POS from the emulator's M4.
  std::string pos;
  for (int i = 0; i < 60; ++i) {
    pos = run(bin + "/tests/rtdb_drive pos");
    int age = -1;
    float x = 0, y = 0, a = 0;
    if (std::sscanf(pos.c_str(), "CMD_POS %f %f %f age %d", &x, &y, &a, &age) == 4 && age >= 0 && age < 1000 &&
        handler.output().find("agent 1") != std::string::npos) {
      break;
    }
    std::this_thread::sleep_for(500ms);
  }
  // Real time on an emulated machine, where the emulator may fall behind the
  // wall clock while other tests load the host: CMD_VEL (0.5 m/s forward) in
  // one-second slices until the robot has gone 0.5 m, at most ten; the
  // outcome, not the exact distance (the virtual-time test checks 1.0 m +- 0.1).
  float px = 0, py = 0, pa = 0;
  int age = -1;
  int slices = 0;
  while (slices < 10 && py <= 0.5F) {
    const std::string drive = run(bin + "/tests/rtdb_drive vel 0 0.5 0 1");
    ++slices;
    ASSERT_EQ(std::sscanf(drive.c_str(), "CMD_POS %f %f %f age %d", &px, &py, &pa, &age), 4)
        << drive << "\nhandler:\n"
        << handler.output() << "\nemulator:\n"
        << emulator.output();
  }
  EXPECT_GT(py, 0.5) << "driven forward by CMD_VEL in " << slices << " one-second slice(s)";
  EXPECT_LT(py, 1.5) << "one slice moves it 0.5 m at most";
  EXPECT_NEAR(px, 0.0, 0.15);
  EXPECT_GE(age, 0);
  EXPECT_LT(age, 1000) << "CMD_POS is kept fresh from M4";
  const int before = m7_seen.load();
  const std::string kick = run(bin + "/tests/rtdb_drive kick 168");  // 0x80 | 40: low kick
  EXPECT_NE(kick.find("CMD_KICKER power 0"), std::string::npos) << kick << handler.output();
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(m7_seen.load() - before, 1) << "the kicker command went out exactly once";
  done = true;
  counter.join();
  handler.stop();
  emulator.stop();
  const std::string summary = handler.output();
  EXPECT_NE(summary.find("kicks sent 1"), std::string::npos) << summary;
  EXPECT_NE(summary.find("latency receive timestamp -> RTDB write"), std::string::npos) << summary;
  std::printf("%s", summary.c_str());
}

}  // namespace
