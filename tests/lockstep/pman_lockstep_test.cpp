// The agent's side of lockstep: a program that behaves as the CAMBADA agent
// does (team_agent: PMan client, sigwait, one cycle per SIGCONT, epilogue)
// runs under the time shim; this test process is canhil (ctest preloads the
// shim into it too, so its PMan stamps activations in virtual time). Each
// frame: move the clock 33 ms, tick the table, wait for the epilogue. In
// virtual time the agent never misses a deadline, however slow the machine.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <string>

#include "canhil/lockstep/conductor.hpp"
#include "canhil/pman/masters.hpp"
#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;
using canhil::lockstep::Conductor;
using canhil::lockstep::Nanos;
using canhil::test::ChildProcess;

constexpr int kAgent = 6;  // a table of its own (the PMan tests run one at a time)

TEST(PmanLockstep, TheAgentRunsOneCycleAFrameAndNeverMissesItsDeadline) {
  Conductor conductor;
  ASSERT_TRUE(conductor.clocks_virtual_here()) << "ctest preloads the shim into this test (tests/CMakeLists.txt)";
  auto masters = canhil::pman::builtin_masters();
  masters->open(kAgent, {"agent" + std::to_string(kAgent)});
  std::string command = "env AGENT=" + std::to_string(kAgent) +
                        " TEAM_RTDB_KEY=" + std::to_string(0x7E200000 + ((getpid() & 0xFFF) << 8));
  for (const std::string& e : conductor.environment(CANHIL_TEST_TIMESHIM, nullptr)) command += " " + e;
  ChildProcess agent(command + " " + CANHIL_TEST_TEAM_AGENT + " --ini " + canhil::test::source_dir() +
                         "/tests/support/cambada_like/config/rtdb.ini",
                     "/tmp/canhil_lockstep_team_agent.log");
  ASSERT_GE(conductor.wait_attached(1, 10s), 1u) << agent.output();

  // Until it has attached (it may be retrying in a virtual sleep).
  Nanos now{0};
  bool attached = false;
  for (int step = 0; step < 100 && !attached; ++step) {
    ASSERT_EQ(conductor.wait_quiet({}, "its start"), "") << agent.output();
    for (const auto& p : masters->query(kAgent)) attached = attached || p.pid != 0;
    now += 33ms;
    conductor.set_time(now);
  }
  ASSERT_TRUE(attached) << agent.output();

  constexpr int kFrames = 60;
  for (int frame = 0; frame < kFrames; ++frame) {
    now += 33ms;
    conductor.set_time(now);
    ASSERT_EQ(masters->tick(kAgent), 1) << "frame " << frame;
    conductor.nudge();
    const std::string stuck = conductor.wait_quiet(
        [&] { return masters->all_idle(kAgent) ? std::string() : std::string("its PMAN_epilogue"); },
        "the frame at " + std::to_string(now.count()) + " ns");
    ASSERT_EQ(stuck, "") << agent.output();
  }
  masters->tick(kAgent);  // counts the last frame's epilogue (and starts one more cycle, waited for)
  conductor.nudge();
  ASSERT_EQ(conductor.wait_quiet([&] { return masters->all_idle(kAgent) ? std::string() : std::string("x"); }, "end"),
            "");
  const auto counts = masters->counts(kAgent);
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].activations, static_cast<std::uint64_t>(kFrames + 1));
  EXPECT_EQ(counts[0].epilogues, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(counts[0].deadline_misses, 0u) << "every cycle ended before the next frame";
  masters->close_all();  // the agent ends (SIGINT), with its counts
  agent.stop();
  EXPECT_NE(agent.output().find("team_agent: cycles " + std::to_string(kFrames + 1)), std::string::npos)
      << agent.output();
}

}  // namespace
