// The external driver on a real vcan (the vcan suite): canhil's reference
// handler and agent as their own processes under the time shim, in lockstep
// with the emulated robot. Same scenario, same binaries: the same trace.
#include "canhil/emulator/external_driver.hpp"

#include <gtest/gtest.h>

#include <string>

#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;
using canhil::test::ChildProcess;

struct Outcome {
  std::string trace;
  double robot_x = 0;
  std::uint64_t from_processes = 0;
  std::string agent_log;
};

Outcome run_once(const std::string& tag, const std::string& handler_extra) {
  lockstep::Conductor conductor;
  Scenario scenario = load_scenario(test::source_dir() + "/emulator/scenarios/one_robot.toml");
  SessionOptions options;
  options.messages = frames::MessageSet::load(test::shipped_dbc());
  Session session(scenario, options);
  ExternalDriver driver(session, conductor);
  std::string env = "env AGENT=1";
  for (const std::string& e : conductor.environment(CANHIL_TEST_TIMESHIM, nullptr)) env += " " + e;
  const std::string bin = test::build_dir() + "/laptop/";
  ChildProcess handler(env + " " + handler_extra + bin + "canhil-hwcomm --iface vcan0", "/tmp/canhil_ext_hw_" + tag);
  ChildProcess agent(env + " " + bin + "canhil-agent --pose -3,0,-90", "/tmp/canhil_ext_agent_" + tag);
  EXPECT_GE(conductor.wait_attached(2, 60s), 2u) << handler.output() << agent.output();
  try {
    driver.run_until(6s);
  } catch (const ProcessStuck& e) {
    ADD_FAILURE() << e.what() << "\n" << handler.output() << agent.output();
  }
  Outcome out{driver.trace(), session.snapshot().robots[0].x_m, driver.frames_from_processes(), ""};
  conductor.release();  // the run is over: their waits end, they take their SIGINT
  handler.stop();
  agent.stop();
  out.agent_log = agent.output();
  return out;
}

TEST(VcanExternal, TheReferenceHandlerAndAgentAsProcessesGiveTheSameTraceTwice) {
  const Outcome a = run_once("a", "");
  const Outcome b = run_once("b", "");
  EXPECT_GT(a.from_processes, 500u) << "the handler answered its trigger messages (M6 at 10 ms)";
  EXPECT_GT(a.robot_x, -2.5) << "the agent drove the robot from x = -3\n" << a.agent_log;
  EXPECT_EQ(a.trace, b.trace) << "same scenario, same binaries: the same trace";
  EXPECT_EQ(a.robot_x, b.robot_x);
}

}  // namespace
}  // namespace canhil::emulator
