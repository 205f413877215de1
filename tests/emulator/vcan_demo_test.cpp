// The README demo in real time over a real vcan: `canhil run` with the
// one-robot scenario (nodes, physics, vision into the RTDB), the reference
// handler canhil-hwcomm and the reference agent canhil-agent, each its own
// process as on a robot. Checks the outcome (the ball went toward the
// opponent goal), never timing: real time here is an emulated machine.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;

TEST(VcanDemo, OneRobotInRealTimeKicksTheBallTowardTheGoal) {
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  setenv("AGENT", "1", 1);
  const std::string bin = canhil::test::build_dir();
  canhil::test::ChildProcess emulator(bin + "/app/canhil run --config " + canhil::test::source_dir() +
                                          "/emulator/scenarios/one_robot.toml --duration 30 --quiet",
                                      "/tmp/canhil_vcan_demo_run.log");
  std::this_thread::sleep_for(1s);  // the emulator creates the RTDB and starts the bus
  canhil::test::ChildProcess handler(bin + "/laptop/canhil-hwcomm --iface vcan0", "/tmp/canhil_vcan_demo_hwcomm.log");
  canhil::test::ChildProcess agent(bin + "/laptop/canhil-agent --pose -3,0,-90 --duration 40",
                                   "/tmp/canhil_vcan_demo_agent.log");
  // The emulator ends by itself after its 30 s and prints its summary.
  for (int i = 0; i < 90 && emulator.output().find("canhil run: done") == std::string::npos; ++i) {
    std::this_thread::sleep_for(500ms);
  }
  const std::string out = emulator.output();
  agent.stop();
  handler.stop();
  emulator.stop();
  const std::string context = out + "\nhandler:\n" + handler.output() + "\nagent:\n" + agent.output();
  const auto at = out.find("ball at (");
  ASSERT_NE(at, std::string::npos) << context;
  float x = 0, y = 0;
  ASSERT_EQ(std::sscanf(out.c_str() + at, "ball at (%f, %f)", &x, &y), 2) << context;
  // The ball starts at (-1, 1); a kick toward the +x goal carries it metres on.
  EXPECT_GT(x, 2.0) << "the ball went toward the opponent goal\n" << context;
  EXPECT_LT(std::abs(y), 3.0) << context;
  EXPECT_NE(out.find("0 bad frames"), std::string::npos) << context;
}

TEST(VcanDemo, KillingTheHandlerLeavesTheEmulatorRunningAndTheMotorsBraked) {
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8) + 0x40).c_str(), 1);
  setenv("AGENT", "1", 1);
  const std::string bin = canhil::test::build_dir();
  canhil::test::ChildProcess emulator(bin + "/app/canhil run --config " + canhil::test::source_dir() +
                                          "/emulator/scenarios/one_robot.toml --duration 18",
                                      "/tmp/canhil_vcan_kill_run.log");
  std::this_thread::sleep_for(1s);
  canhil::test::ChildProcess handler(bin + "/laptop/canhil-hwcomm --iface vcan0", "/tmp/canhil_vcan_kill_hwcomm.log");
  std::this_thread::sleep_for(2s);
  // Sideways (robot -x is world +y here), away from the ball, for longer than the handler lives.
  canhil::test::ChildProcess drive(bin + "/tests/rtdb_drive vel -0.3 0 0 10", "/tmp/canhil_vcan_kill_drive.log");
  std::this_thread::sleep_for(4s);
  handler.kill_with(SIGKILL);  // no goodbye: the M6 stream just stops
  for (int i = 0; i < 60 && emulator.output().find("canhil run: done") == std::string::npos; ++i) {
    std::this_thread::sleep_for(500ms);
  }
  drive.stop();
  const std::string out = emulator.output();
  const int status = emulator.stop();
  ASSERT_NE(out.find("canhil run: done"), std::string::npos) << "the emulator kept running to its end\n" << out;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << out;
  // Progress lines: "t=  5.0 s  ball (...)  vcan0 (x, y)  late steps N".
  std::vector<std::pair<float, float>> poses;
  for (std::size_t at = out.find("vcan0 ("); at != std::string::npos; at = out.find("vcan0 (", at + 1)) {
    float x = 0, y = 0;
    if (std::sscanf(out.c_str() + at, "vcan0 (%f, %f)", &x, &y) == 2) poses.emplace_back(x, y);
  }
  ASSERT_GE(poses.size(), 8u) << out;
  const auto& last = poses.back();
  EXPECT_GT(std::hypot(last.first - (-3.0F), last.second - 0.0F), 0.3F) << "it drove while the handler lived\n" << out;
  for (std::size_t k = poses.size() - 4; k < poses.size(); ++k) {
    EXPECT_NEAR(poses[k].first, last.first, 0.02) << "braked: it stays where it stopped\n" << out;
    EXPECT_NEAR(poses[k].second, last.second, 0.02) << out;
  }
}

TEST(VcanDemo, InterfaceDownAndUpIsReportedAndTheRunResumesWithoutABurst) {
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8) + 0x80).c_str(), 1);
  const std::string bin = canhil::test::build_dir();
  canhil::test::ChildProcess emulator(bin + "/app/canhil run --config " + canhil::test::source_dir() +
                                          "/emulator/scenarios/one_robot.toml --duration 12 --quiet",
                                      "/tmp/canhil_vcan_updown_run.log");
  std::this_thread::sleep_for(3s);
  ASSERT_EQ(std::system("ip link set vcan0 down"), 0);
  std::this_thread::sleep_for(1s);  // about 100 trigger messages not sent
  ASSERT_EQ(std::system("ip link set vcan0 up"), 0);
  const canhil::can_nodes::WallClock clock;
  const canhil::can_nodes::Nanos up = clock.now();
  auto bus = canhil::can_nodes::SocketCanBus::open("vcan0");  // only what is sent from now on
  const canhil::can_nodes::Filter tm[] = {canhil::can_nodes::Filter::exact(0x010)};
  bus->set_filters(tm);
  std::vector<canhil::can_nodes::Nanos> tms;
  while (clock.now() < up + 2s) {
    if (bus->wait_readable(50ms)) {
      while (auto f = bus->receive()) tms.push_back(f->time);
    }
  }
  for (int i = 0; i < 40 && emulator.output().find("canhil run: done") == std::string::npos; ++i) {
    std::this_thread::sleep_for(500ms);
  }
  const std::string out = emulator.output();
  emulator.stop();
  EXPECT_NE(out.find("canhil run: vcan0 is down"), std::string::npos) << out;
  EXPECT_NE(out.find("canhil run: vcan0 is up"), std::string::npos) << out;
  EXPECT_NE(out.find("canhil run: done"), std::string::npos) << "the run went on to its end\n" << out;
  ASSERT_FALSE(tms.empty()) << "no trigger message after the interface came back\n" << out;
  EXPECT_LT(tms.front() - up, 1s) << "the run resumed within a second";
  // No catch-up burst of the ECs missed while down: at most one TM per EC
  // (10 ms) over the first second back, with slack for a late wake-up.
  const auto in_first_second =
      std::count_if(tms.begin(), tms.end(), [&](canhil::can_nodes::Nanos t) { return t < tms.front() + 1s; });
  std::printf("down/up: first TM %.1f ms after up; %ld TMs in the first second back\n",
              std::chrono::duration<double, std::milli>(tms.front() - up).count(), static_cast<long>(in_first_second));
  EXPECT_LE(in_first_second, 105) << out;
  // Flowing again: a count, not a rate (under ASan inside the TCG VM the emulator
  // runs at a third of real time and skips physics steps to keep up).
  EXPECT_GE(tms.size(), 10u) << "trigger messages flow again\n" << out;
}

}  // namespace
