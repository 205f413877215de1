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

// Positions "TAG(x, y)" in the progress lines ("t=  5.0 s  ball (...)  vcan0 (x, y)  late steps N"), in order.
std::vector<std::pair<float, float>> positions(const std::string& out, const std::string& tag) {
  std::vector<std::pair<float, float>> found;
  const std::string format = tag + "(%f, %f)";
  for (std::size_t at = out.find(tag + "("); at != std::string::npos; at = out.find(tag + "(", at + 1)) {
    float x = 0, y = 0;
    if (std::sscanf(out.c_str() + at, format.c_str(), &x, &y) == 2) found.emplace_back(x, y);
  }
  return found;
}

// Polls the program's output until `done(output)` or `limit` has passed. The
// limits are generous: under TCG on a loaded machine the emulator has been
// seen to run physics at half of real time, so waits are for outcomes, not for
// a fixed number of seconds.
template <class Done>
bool wait_for(const canhil::test::ChildProcess& program, std::chrono::seconds limit, Done done) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (!done(program.output())) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(250ms);
  }
  return true;
}

TEST(VcanDemo, OneRobotInRealTimeKicksTheBallTowardTheGoal) {
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  setenv("AGENT", "1", 1);
  const std::string bin = canhil::test::build_dir();
  canhil::test::ChildProcess emulator(
      bin + "/app/canhil run --config " + canhil::test::source_dir() + "/emulator/scenarios/one_robot.toml",
      "/tmp/canhil_vcan_demo_run.log");
  std::this_thread::sleep_for(1s);  // the emulator creates the RTDB and starts the bus
  canhil::test::ChildProcess handler(bin + "/laptop/canhil-hwcomm --iface vcan0", "/tmp/canhil_vcan_demo_hwcomm.log");
  canhil::test::ChildProcess agent(bin + "/laptop/canhil-agent --pose -3,0,-90", "/tmp/canhil_vcan_demo_agent.log");
  // Until the ball is well on its way to the +x goal (about 6 s on a quiet machine).
  wait_for(emulator, 90s, [](const std::string& out) {
    const auto ball = positions(out, "ball ");
    return !ball.empty() && ball.back().first > 2.0F;
  });
  agent.stop();
  handler.stop();
  const int status = emulator.stop();  // Ctrl-C: the run ends with its summary
  const std::string out = emulator.output();
  const std::string context = out + "\nhandler:\n" + handler.output() + "\nagent:\n" + agent.output();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << "Ctrl-C ends the run as a shell expects\n" << context;
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
  canhil::test::ChildProcess emulator(
      bin + "/app/canhil run --config " + canhil::test::source_dir() + "/emulator/scenarios/one_robot.toml",
      "/tmp/canhil_vcan_kill_run.log");
  std::this_thread::sleep_for(1s);
  canhil::test::ChildProcess handler(bin + "/laptop/canhil-hwcomm --iface vcan0", "/tmp/canhil_vcan_kill_hwcomm.log");
  std::this_thread::sleep_for(2s);
  // Sideways (robot -x is world +y here), away from the ball, for longer than the handler lives.
  canhil::test::ChildProcess drive(bin + "/tests/rtdb_drive vel -0.3 0 0 300", "/tmp/canhil_vcan_kill_drive.log");
  const auto moved = [](const std::pair<float, float>& p) { return std::hypot(p.first - (-3.0F), p.second) > 0.3F; };
  const bool drove = wait_for(emulator, 90s, [&](const std::string& out) {
    const auto robot = positions(out, "vcan0 ");
    return !robot.empty() && moved(robot.back());
  });
  ASSERT_TRUE(drove) << "it drove while the handler lived\n" << emulator.output();
  handler.kill_with(SIGKILL);  // no goodbye: the M6 stream just stops
  const std::size_t at_kill = positions(emulator.output(), "vcan0 ").size();
  // Eight more progress lines (about 8 s): the emulator runs on, the robot stops.
  const bool ran_on =
      wait_for(emulator, 90s, [&](const std::string& out) { return positions(out, "vcan0 ").size() >= at_kill + 8; });
  drive.stop();
  const int status = emulator.stop();
  const std::string out = emulator.output();
  ASSERT_TRUE(ran_on) << "the emulator kept running after the handler died\n" << out;
  ASSERT_NE(out.find("canhil run: stopped after"), std::string::npos) << "Ctrl-C ends the run with its summary\n"
                                                                      << out;
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << out;
  const auto poses = positions(out, "vcan0 ");
  const auto& last = poses.back();
  EXPECT_TRUE(moved(last)) << out;
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
