// A team's laptop software, unchanged, against canhil on a real vcan: a
// program that behaves as the CAMBADA agent does (tests/laptop/team_agent.cpp:
// PMan client, one cycle per SIGCONT, CAMBADA's items and units) on the
// team's own RTDB library (the stand-in) and a PMan library with CAMBADA's
// API; `canhil run` loads both (--rtdb-lib, --pman-lib) in CAMBADA's layout,
// `canhil-hwcomm` serves the same RTDB. Order, counts and outcomes are
// checked, never timing (real time in the VM is slow and noisy).
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/session_test.cpp, in CAMBADA's layout).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;
using canhil::test::ChildProcess;

template <class Done>
bool wait_for(const ChildProcess& program, std::chrono::seconds limit, Done done) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (!done(program.output())) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(250ms);
  }
  return true;
}
bool has(const std::string& out, const std::string& text) { return out.find(text) != std::string::npos; }

// The last "ball (x, y)" and "vcan0 (x, y)" of the run's progress lines, and
// where the ball was on the first.
struct Progress {
  float ball_x = 0, ball_y = 0, robot_x = 0, robot_y = 0;
  float first_ball_x = 0, first_ball_y = 0;
  int lines = 0;
};
Progress progress(const std::string& out) {
  Progress p;
  for (std::size_t at = out.find("  t="); at != std::string::npos; at = out.find("  t=", at + 1)) {
    float t = 0;
    if (std::sscanf(out.c_str() + at, "  t=%f s  ball (%f, %f)  vcan0 (%f, %f)", &t, &p.ball_x, &p.ball_y, &p.robot_x,
                    &p.robot_y) == 5) {
      if (p.lines == 0) {
        p.first_ball_x = p.ball_x;
        p.first_ball_y = p.ball_y;
      }
      ++p.lines;
    }
  }
  return p;
}

struct AgentCounts {
  long cycles = -1, before_vision = -1, playing = -1, stopped = -1, kicks = -1;
};
AgentCounts last_counts(const std::string& out) {
  AgentCounts c;
  const auto at = out.rfind("team_agent: cycles ");
  if (at != std::string::npos) {
    std::sscanf(out.c_str() + at, "team_agent: cycles %ld, before vision %ld, playing %ld, stopped %ld, kicks %ld",
                &c.cycles, &c.before_vision, &c.playing, &c.stopped, &c.kicks);
  }
  return c;
}

std::string run_canhil(const std::string& args) {
  std::string out;
  FILE* p = popen((canhil::test::build_dir() + "/app/canhil " + args + " 2>&1").c_str(), "r");
  if (p == nullptr) return out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p) != nullptr) out += buf;
  pclose(p);
  return out;
}

TEST(VcanTeamAgent, TheTeamsAgentOnItsOwnLibrariesDrivesToTheBallAndStopsWhenTheCoachSaysSo) {
  setenv("AGENT", "1", 1);
  setenv("TEAM_RTDB_KEY", std::to_string(0x7E000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  const std::string team = canhil::test::source_dir() + "/tests/support/cambada_like/";
  const std::string libs = std::string(" --rtdb-lib ") + CANHIL_TEST_TEAM_RTDB + " --rtdb-items " + team +
                           "rtdb_user.h --rtdb-ini " + team + "config/rtdb.ini --layout cambada";
  // The team's agent first, as a robot's start-up script may: it waits for its master.
  ChildProcess agent(std::string(CANHIL_TEST_TEAM_AGENT) + " --ini " + team + "config/rtdb.ini",
                     "/tmp/canhil_vcan_team_agent.log");
  ChildProcess stranger(std::string(CANHIL_TEST_TEAM_AGENT) + " --ini " + team + "config/rtdb.ini --name agent9",
                        "/tmp/canhil_vcan_team_stranger.log");
  ASSERT_TRUE(wait_for(agent, 30s, [](const std::string& o) { return has(o, "no PMan table yet, waiting"); }))
      << agent.output();
  ChildProcess emulator(canhil::test::build_dir() + "/app/canhil run --config " + canhil::test::source_dir() +
                            "/emulator/scenarios/one_robot.toml --duration 0" + libs + " --pman-lib " +
                            CANHIL_TEST_LIBPMAN,
                        "/tmp/canhil_vcan_team_run.log");
  ASSERT_TRUE(wait_for(emulator, 60s, [](const std::string& o) { return has(o, "robot 0 on vcan0"); }))
      << emulator.output();
  ChildProcess handler(canhil::test::build_dir() + "/laptop/canhil-hwcomm --iface vcan0" + libs,
                       "/tmp/canhil_vcan_team_hwcomm.log");
  ASSERT_TRUE(wait_for(agent, 60s, [](const std::string& o) { return has(o, "attached as agent1"); }))
      << agent.output() << "\nrun:\n"
      << emulator.output();
  // A process the table does not name is refused, and only it.
  ASSERT_TRUE(wait_for(stranger, 60s, [](const std::string& o) { return has(o, "agent9 is not in the PMan table"); }))
      << stranger.output();
  const std::optional<int> stranger_status = stranger.wait_end(60s);  // it ends by itself
  ASSERT_TRUE(stranger_status.has_value()) << stranger.output();
  EXPECT_TRUE(WIFEXITED(*stranger_status) && WEXITSTATUS(*stranger_status) == 4) << stranger.output();

  // Drives to the ball (the ball starts 2 m ahead of the robot and 1 m to its
  // left). Progress lines come once a second and the agent kicks as soon as it
  // holds the ball, so the robot is checked against where the ball lay, not
  // where it is now: a line between arrival and kick may never be printed.
  const bool reached = wait_for(emulator, 150s, [](const std::string& o) {
    const Progress p = progress(o);
    return p.lines > 0 && std::hypot(p.first_ball_x - p.robot_x, p.first_ball_y - p.robot_y) < 0.45F;
  });
  const std::string context = "\nrun:\n" + emulator.output() + "\nagent:\n" + agent.output() + "\nhandler:\n";
  ASSERT_TRUE(reached) << context << handler.output();
  EXPECT_TRUE(has(agent.output(), "coach says play")) << context;

  // canhil pman list: the agent attached, activated.
  const std::string list = run_canhil("pman list");
  // Agent 1's table and the line under it (a table left on this machine by
  // another run, killed before it could remove it, is listed too: not ours).
  const auto table = list.find("agent 1: table at key 0x9013");
  ASSERT_NE(table, std::string::npos) << list;
  const auto line_start = list.find('\n', table) + 1;
  const std::string ours = list.substr(line_start, list.find('\n', line_start) - line_start);
  EXPECT_TRUE(has(ours, "agent1")) << list;
  EXPECT_FALSE(has(ours, "not attached")) << list;

  // The coach says stop: the agent stops, the robot stands.
  const std::string coach = run_canhil("coach stop");
  EXPECT_TRUE(has(coach, "game state: stop")) << "shown once the run has taken the order\n" << coach;
  ASSERT_TRUE(wait_for(agent, 30s, [](const std::string& o) { return has(o, "coach says stop"); })) << context;
  const AgentCounts at_stop = last_counts(agent.output());
  EXPECT_EQ(at_stop.before_vision, 0) << "never woken before its VISION_INFO was written\n" << agent.output();
  EXPECT_GT(at_stop.playing, 10) << agent.output();
  std::this_thread::sleep_for(1500ms);  // the robot brakes
  const int lines_then = progress(emulator.output()).lines;
  ASSERT_TRUE(wait_for(emulator, 30s, [&](const std::string& o) { return progress(o).lines >= lines_then + 2; }));
  const Progress a = progress(emulator.output());
  ASSERT_TRUE(wait_for(emulator, 30s, [&](const std::string& o) { return progress(o).lines >= a.lines + 2; }));
  const Progress b = progress(emulator.output());
  EXPECT_LT(std::hypot(b.robot_x - a.robot_x, b.robot_y - a.robot_y), 0.1F) << "stopped by the coach" << context;

  // The agent dies without a word: the run goes on, and counts what it misses.
  agent.kill_with(SIGKILL);
  const int lines_at_death = progress(emulator.output()).lines;
  EXPECT_TRUE(wait_for(emulator, 30s, [&](const std::string& o) { return progress(o).lines >= lines_at_death + 2; }))
      << "the run goes on after its agent died" << context;
  handler.stop();
  const int status = emulator.stop();
  const std::string out = emulator.output();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << out;
  EXPECT_TRUE(has(out, "PMan: " + std::string(CANHIL_TEST_LIBPMAN))) << out;
  const auto at = out.find("agent 1 agent1: ");
  ASSERT_NE(at, std::string::npos) << out;
  long activations = 0, epilogues = 0, misses = 0, gone = 0;
  ASSERT_EQ(std::sscanf(out.c_str() + at,
                        "agent 1 agent1: %ld activations, %ld epilogues, %ld deadline misses, %ld times gone",
                        &activations, &epilogues, &misses, &gone),
            4)
      << out;
  EXPECT_GE(activations, at_stop.cycles) << "every cycle the agent ran was an activation canhil counted";
  EXPECT_GE(epilogues, at_stop.cycles - 1) << out;
  EXPECT_EQ(gone, 1) << "the agent's death was seen and reported\n" << out;
  EXPECT_TRUE(has(out, "RTDB: " + std::string(CANHIL_TEST_TEAM_RTDB))) << out;
  EXPECT_TRUE(has(handler.output(), "layout cambada")) << handler.output();
}

// The run script's log folder and the script's own output, once a test passed
// (named by the test's pid: two suites at once write apart).
void remove_logs(const std::string& logs) {
  std::error_code ignored;
  std::filesystem::remove_all(logs, ignored);
  std::filesystem::remove(logs + ".log", ignored);
}

TEST(VcanTeamAgent, TheRunScriptStartsAllThreeAndStopsThemTogether) {
  setenv("AGENT", "1", 1);
  setenv("TEAM_RTDB_KEY", std::to_string(0x7E100000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  const std::string src = canhil::test::source_dir();
  const std::string team = src + "/tests/support/cambada_like/";
  const std::string logs = "/tmp/canhil_vcan_own_software_" + std::to_string(getpid());
  ChildProcess script("bash " + src + "/scripts/run-own-software.sh --canhil " + canhil::test::build_dir() +
                          " --logs " + logs + " --rtdb-lib " + CANHIL_TEST_TEAM_RTDB + " --rtdb-items " + team +
                          "rtdb_user.h --rtdb-ini " + team + "config/rtdb.ini --layout cambada --pman-lib " +
                          CANHIL_TEST_LIBPMAN + " -- " + CANHIL_TEST_TEAM_AGENT + " --ini " + team + "config/rtdb.ini",
                      logs + ".log");
  ASSERT_TRUE(wait_for(script, 60s, [](const std::string& o) { return has(o, "== running"); })) << script.output();
  std::this_thread::sleep_for(5s);
  script.stop();  // Ctrl-C
  const std::string out = script.output();
  EXPECT_TRUE(has(out, "== canhil run's summary")) << out;
  const auto at = out.find("agent 1 agent1: ");
  ASSERT_NE(at, std::string::npos) << out;
  long activations = 0;
  ASSERT_EQ(std::sscanf(out.c_str() + at, "agent 1 agent1: %ld activations", &activations), 1) << out;
  EXPECT_GT(activations, 0) << out;
  std::FILE* f = std::fopen((logs + "/agent.log").c_str(), "r");
  ASSERT_NE(f, nullptr);
  std::string agent_log;
  char buf[256];
  while (std::fgets(buf, sizeof buf, f) != nullptr) agent_log += buf;
  std::fclose(f);
  EXPECT_TRUE(has(agent_log, "team_agent: cycles")) << "the agent ended when the run closed its table\n" << agent_log;
  if (!HasFailure()) remove_logs(logs);
}

TEST(VcanTeamAgent, TheRunScriptEndsWhenTheAgentFailsAtOnce) {
  // The agent fails while the handler is still starting: the script stops the
  // handler and the run whatever their start-up state, and says why it ended
  // (it hung for good when a SIGINT reached the handler before its handler
  // of SIGINT was installed: a script's background job starts with SIGINT
  // ignored). Twice, since the race is in the start-up.
  const std::string src = canhil::test::source_dir();
  for (int round = 0; round < 2; ++round) {
    const std::string logs = "/tmp/canhil_vcan_own_software_fails_" + std::to_string(getpid());
    ChildProcess script("bash " + src + "/scripts/run-own-software.sh --canhil " + canhil::test::build_dir() +
                            " --logs " + logs + " -- sh -c 'echo the agent gives up; exit 3'",
                        logs + ".log");
    const std::optional<int> status = script.wait_end(120s);
    ASSERT_TRUE(status.has_value()) << "the script ended by itself (round " << round << ")\n" << script.output();
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 1) << script.output();
    const std::string out = script.output();
    EXPECT_TRUE(has(out, "== the agent ended with status 3")) << out;
    EXPECT_TRUE(has(out, "the agent gives up")) << "the end of its log\n" << out;
    EXPECT_TRUE(has(out, "== canhil run's summary")) << out;
    if (HasFailure()) break;
    remove_logs(logs);
  }
}

TEST(VcanTeamAgent, TheRunScriptRefusesAnInterfaceTheScenarioDoesNotUse) {
  const std::string src = canhil::test::source_dir();
  const std::string logs = "/tmp/canhil_vcan_own_software_wrong_" + std::to_string(getpid());
  ChildProcess script("bash " + src + "/scripts/run-own-software.sh --canhil " + canhil::test::build_dir() +
                          " --iface vcan7 --logs " + logs + " -- /bin/sleep 30",
                      logs + ".log");
  // The script ends by itself: stopping it once its refusal shows would race
  // its exit (a SIGINT between the message and `exit 2` ends it by signal).
  const std::optional<int> status = script.wait_end(60s);
  ASSERT_TRUE(status.has_value()) << "the script ended by itself\n" << script.output();
  EXPECT_TRUE(has(script.output(), "no robot on vcan7")) << script.output();
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 2) << script.output();
  EXPECT_TRUE(has(script.output(), "robot 0 on vcan0 (") && has(script.output(), ") for agent 1"))
      << "what the run does use\n"
      << script.output();
  EXPECT_FALSE(has(script.output(), "== the agent")) << "nothing else was started\n" << script.output();
  if (!HasFailure()) remove_logs(logs);
}

}  // namespace
