// `canhil run --external` on a real vcan (the vcan suite): canhil's reference
// handler and agent as processes of their own, under the time shim, in
// lockstep with the emulated robot. The same scenario and binaries give the
// same trace byte for byte, however slow the handler is; the robot scores as
// in the in-process virtual-time run; a handler that stops answering is named
// and the trace is still written. Wall time never decides a result here: it
// only bounds how long a run may take.
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/virtual_driver_test.cpp, handler_participant_test.cpp).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "support/test_paths.hpp"

namespace {

struct Finished {
  int status = -1;
  std::string output;
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs canhil to its end (at most five minutes), its output captured.
Finished canhil(const std::string& arguments, const std::string& tag) {
  const std::string log = "/tmp/canhil_external_" + tag + "_" + std::to_string(getpid()) + ".out";
  const std::string command = "timeout 300 " + canhil::test::canhil_binary() + " " + arguments + " > " + log + " 2>&1";
  Finished f;
  f.status = std::system(command.c_str());
  f.output = read_file(log);
  std::remove(log.c_str());
  return f;
}

// The first line where two traces part, with the line before.
std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream in_a(a), in_b(b);
  std::string line_a, line_b, before;
  for (int line = 1;; ++line) {
    const bool more_a = static_cast<bool>(std::getline(in_a, line_a));
    const bool more_b = static_cast<bool>(std::getline(in_b, line_b));
    if (!more_a && !more_b) return "none";
    if (!more_a || !more_b || line_a != line_b) {
      return "line " + std::to_string(line) + ", after " + before + "\n  a: " + (more_a ? line_a : "(end)") +
             "\n  b: " + (more_b ? line_b : "(end)");
    }
    before = line_a;
  }
}

int exit_status(const Finished& f) { return WIFEXITED(f.status) ? WEXITSTATUS(f.status) : -1; }

std::string trace_path(const std::string& tag) {
  return "/tmp/canhil_external_" + tag + "_" + std::to_string(getpid()) + ".log";
}

const std::string kRun =
    "run --no-control --quiet --config " + canhil::test::source_dir() + "/emulator/scenarios/one_robot.toml";
const std::string kAgent = " --process \"canhil-agent --pose -3,0,-90\"";

// "GOAL at T s in the +x (opponent) goal": T, or -1.
double opponent_goal_at(const std::string& output) {
  const auto at = output.find("GOAL at ");
  if (at == std::string::npos || output.find("+x (opponent)", at) == std::string::npos) return -1;
  return std::atof(output.c_str() + at + 8);
}

// "canhil's looks before sleeping ([external] spin_us): A answered, S ended
// in a sleep": A and S, both 0 when the line is missing.
struct Looks {
  unsigned long long answered = 0;
  unsigned long long slept = 0;
};
Looks looks_of(const std::string& output) {
  const std::string line = "canhil's looks before sleeping ([external] spin_us): ";
  const auto at = output.find(line);
  if (at == std::string::npos) return {};
  char* end = nullptr;
  Looks looks;
  looks.answered = std::strtoull(output.c_str() + at + line.size(), &end, 10);
  const std::string between = " answered, ";
  if (output.compare(static_cast<std::size_t>(end - output.c_str()), between.size(), between) != 0) return {};
  looks.slept = std::strtoull(end + between.size(), nullptr, 10);
  return looks;
}

TEST(VcanExternal, TheReferenceHandlerAndAgentGiveTheSameTraceTwiceAndScoreAsInProcess) {
  const std::string tail = " --external --duration 6 --process \"canhil-hwcomm --iface {iface}\"" + kAgent;
  const Finished a = canhil(kRun + tail + " --trace " + trace_path("a") + " --world-log " + trace_path("world_a"), "a");
  // The second time canhil and the bus's broker sleep at once instead of looking on: only the waiting differs.
  const std::string sleeping = trace_path("sleeping") + ".toml";
  {
    std::ofstream out(sleeping);
    out << read_file(canhil::test::source_dir() + "/emulator/scenarios/one_robot.toml")
        << "\n[external]\nspin_us = 0\nbus_spin_us = 0\n";
  }
  const Finished b = canhil("run --no-control --quiet --config " + sleeping + tail + " --trace " + trace_path("b") +
                                " --world-log " + trace_path("world_b"),
                            "b");
  std::remove(sleeping.c_str());
  ASSERT_EQ(exit_status(a), 0) << a.output;
  ASSERT_EQ(exit_status(b), 0) << b.output;
  // Looking on, most looks find what canhil waits for; with spin_us 0 a look
  // is one glance at the bus's counts, which finds a frame only when one came
  // in the instant since canhil asked: nearly every wait ends in a sleep.
  const Looks looked = looks_of(a.output);
  const Looks glanced = looks_of(b.output);
  ASSERT_GE(looked.answered + looked.slept, 1u) << a.output;
  ASSERT_GE(glanced.answered + glanced.slept, 1u) << b.output;
  EXPECT_GT(looked.answered, glanced.answered) << a.output << b.output;
  EXPECT_LT(glanced.answered * 10, glanced.slept) << b.output;
  const std::string trace_a = read_file(trace_path("a"));
  const std::string trace_b = read_file(trace_path("b"));
  EXPECT_GT(trace_a.size(), 10'000u) << "six seconds of a robot's bus";
  EXPECT_NE(trace_a.find(" vcan0 131#"), std::string::npos) << "the handler's M6_1 is on the bus";
  EXPECT_TRUE(trace_a == trace_b) << "same scenario, same binaries: the same trace (" << trace_a.size() << " and "
                                  << trace_b.size() << " bytes); first difference:\n"
                                  << first_difference(trace_a, trace_b);
  if (trace_a != trace_b) return;  // both traces kept for a look
  const std::string world_a = read_file(trace_path("world_a"));
  EXPECT_GT(world_a.size(), 1'000u) << "the world log is written";
  EXPECT_TRUE(world_a == read_file(trace_path("world_b"))) << "and is the same too";
  EXPECT_NE(a.output.find("canhil-hwcomm"), std::string::npos) << "the summary names each process\n" << a.output;
  EXPECT_NE(a.output.find("x real time)"), std::string::npos) << a.output;
  // The bus this test runs on (the kernel's vcan or canhil's own), as canhil names it.
  const std::string bus_line = std::string("robot 0 on vcan0 (") + canhil::can_nodes::bus_of("vcan0") + ") for agent 1";
  EXPECT_NE(a.output.find(bus_line), std::string::npos) << "says which bus\n" << a.output;
  const Finished in_process = canhil(kRun + " --virtual-time --duration 6", "in_process");
  const double goal_external = opponent_goal_at(a.output);
  const double goal_in_process = opponent_goal_at(in_process.output);
  ASSERT_GT(goal_in_process, 0) << in_process.output;
  EXPECT_GT(goal_external, 0) << "the robot scores with the handler and agent as processes\n" << a.output;
  EXPECT_NEAR(goal_external, goal_in_process, 0.5) << a.output << in_process.output;
  for (const char* tag : {"a", "b", "world_a", "world_b"}) std::remove(trace_path(tag).c_str());
}

TEST(VcanExternal, AHandlerSpendingFiftyMillisecondsOfWallTimePerBatchGivesTheSameTrace) {
  const std::string run = kRun + " --external --duration 1 --process \"canhil-hwcomm --iface {iface}";
  const Finished fast = canhil(run + "\"" + kAgent + " --trace " + trace_path("fast"), "fast");
  const Finished slow = canhil(run + " --slow-ms 50\"" + kAgent + " --trace " + trace_path("slow"), "slow");
  ASSERT_EQ(exit_status(fast), 0) << fast.output;
  ASSERT_EQ(exit_status(slow), 0) << slow.output;
  const std::string a = read_file(trace_path("fast"));
  const std::string b = read_file(trace_path("slow"));
  EXPECT_GT(a.size(), 1'000u);
  EXPECT_TRUE(a == b) << "the outcome does not depend on the machine's speed (" << a.size() << " and " << b.size()
                      << " bytes); first difference:\n"
                      << first_difference(a, b);
  if (a != b) return;  // both traces kept for a look
  std::remove(trace_path("fast").c_str());
  std::remove(trace_path("slow").c_str());
}

// "team_agent: cycles N, before vision B, ..." (the last one): N and B.
std::pair<long, long> agent_cycles(const std::string& output) {
  long cycles = -1, before_vision = -1;
  const auto at = output.rfind("team_agent: cycles ");
  if (at != std::string::npos)
    std::sscanf(output.c_str() + at, "team_agent: cycles %ld, before vision %ld", &cycles, &before_vision);
  return {cycles, before_vision};
}

TEST(VcanExternal, TheTeamsAgentOnItsOwnLibrariesRunsOncePerVisionFrameAndGivesTheSameTraceTwice) {
  // The CAMBADA-like agent (PMan client, one cycle per SIGCONT) on the team's
  // RTDB library and a PMan library with CAMBADA's API, as in the real-time
  // test, and the handler on the same RTDB; all in virtual time.
  setenv("TEAM_RTDB_KEY", std::to_string(0x7E300000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  const std::string team = canhil::test::source_dir() + "/tests/support/cambada_like/";
  const std::string libs = std::string(" --rtdb-lib ") + CANHIL_TEST_TEAM_RTDB + " --rtdb-items " + team +
                           "rtdb_user.h --rtdb-ini " + team + "config/rtdb.ini --layout cambada";
  const std::string run = kRun + libs + " --pman-lib " + CANHIL_TEST_LIBPMAN +
                          " --external --duration 3 --process \"canhil-hwcomm --iface {iface}" + libs +
                          "\" --process \"" + CANHIL_TEST_TEAM_AGENT + " --ini " + team + "config/rtdb.ini\"";
  const Finished a = canhil(run + " --trace " + trace_path("team_a"), "team_a");
  const Finished b = canhil(run + " --trace " + trace_path("team_b"), "team_b");
  ASSERT_EQ(exit_status(a), 0) << a.output;
  ASSERT_EQ(exit_status(b), 0) << b.output;
  // Vision writes 30 frames a second, from t = 0: 91 in [0, 3 s]; the agent's
  // last cycle may be the one the run ended in.
  const auto [cycles, before_vision] = agent_cycles(a.output);
  EXPECT_GE(cycles, 90) << "activated once per vision frame\n" << a.output;
  EXPECT_LE(cycles, 91) << "and only then\n" << a.output;
  EXPECT_EQ(before_vision, 0) << a.output;
  EXPECT_EQ(agent_cycles(b.output), agent_cycles(a.output)) << b.output;
  // canhil writes VISION_INFO through the team's own library in its own
  // process, the agent reads it in another, both on the lockstep's clock:
  // woken by the frame, the agent finds it fresh, never from the future.
  const auto at = a.output.rfind("vision age ");
  ASSERT_NE(at, std::string::npos) << a.output;
  int youngest = -1000, oldest = -1000;
  ASSERT_EQ(std::sscanf(a.output.c_str() + at, "vision age %d..%d ms", &youngest, &oldest), 2) << a.output;
  EXPECT_GE(youngest, 0) << a.output;
  EXPECT_LE(oldest, 5) << "read within the instant it was written\n" << a.output;
  EXPECT_NE(a.output.find("team_agent: coach says play"), std::string::npos) << a.output;
  const std::string trace_a = read_file(trace_path("team_a"));
  const std::string trace_b = read_file(trace_path("team_b"));
  EXPECT_NE(trace_a.find(" vcan0 131#"), std::string::npos) << "the handler's M6_1 is on the bus";
  EXPECT_TRUE(trace_a == trace_b) << "the same trace (" << trace_a.size() << " and " << trace_b.size()
                                  << " bytes); first difference:\n"
                                  << first_difference(trace_a, trace_b);
  if (trace_a != trace_b) return;  // both traces kept for a look
  std::remove(trace_path("team_a").c_str());
  std::remove(trace_path("team_b").c_str());
}

TEST(VcanExternal, AHandlerThatStopsAnsweringIsNamedAndTheTraceIsKept) {
  // Two seconds of wall time per batch of frames, longer than the answer limit.
  const Finished f = canhil(kRun + " --external --duration 2 --answer-limit 0.5 --process \"canhil-hwcomm --iface " +
                                "{iface} --slow-ms 2000\"" + kAgent + " --trace " + trace_path("stuck"),
                            "stuck");
  EXPECT_EQ(exit_status(f), 3) << f.output;
  EXPECT_NE(f.output.find("canhil-hwcomm (pid"), std::string::npos) << "named\n" << f.output;
  EXPECT_NE(f.output.find("kept running and did not wait again within 0.500 s of wall time"), std::string::npos)
      << f.output;
  const std::string trace = read_file(trace_path("stuck"));
  EXPECT_NE(trace.find(" vcan0 010#"), std::string::npos) << "the trace up to the stop is written\n" << f.output;
  std::remove(trace_path("stuck").c_str());
}

TEST(VcanExternal, AProgramThatIsNotFoundStopsTheRunSayingSo) {
  // A typing error in a command line: the shell starts, attaches and ends
  // with 127. The run stops with exit 3 rather than play on without it.
  const Finished f = canhil(kRun + " --external --duration 4 --process \"canhil-hwcomm --iface {iface}\"" +
                                " --process \"canhil-agnet --pose -3,0,-90\"",
                            "typo");
  EXPECT_EQ(exit_status(f), 3) << f.output;
  EXPECT_NE(f.output.find("`canhil-agnet --pose -3,0,-90` (agent 1, pid "), std::string::npos) << f.output;
  EXPECT_NE(f.output.find("never ran: the shell found no such program (exit status 127); check the command line"),
            std::string::npos)
      << f.output;
}

TEST(VcanExternal, TheBenchPrintsBothFactorsAndWhereTheWallTimeWent) {
  // Wall-clock figures: printed, never judged here (the exit status says met or missed).
  const Finished f = canhil("bench --part external --seconds 2", "bench");
  EXPECT_TRUE(exit_status(f) == 0 || exit_status(f) == 1) << f.output;
  for (const char* line :
       {"in-process, canhil's handler and agent:", "external processes in lockstep:", "target >= 20x",
        "external / in-process, in this run:", "canhil, lockstep work", "canhil-hwcomm    running",
        "canhil-agent     running", "hand-overs", "the floor on this machine: one bare hand-over between two processes",
        "at that cost alone:", ", at best "}) {
    EXPECT_NE(f.output.find(line), std::string::npos) << line << "\n" << f.output;
  }
  EXPECT_NE(f.output.find("all on CPU 0"), std::string::npos) << f.output;
  EXPECT_EQ(f.output.find("NOT MEASURED"), std::string::npos) << f.output;
  EXPECT_NE(f.output.find("canhil's looks before sleeping, up to 50 us each ([external] spin_us): "), std::string::npos)
      << "[external] spin_us's default\n"
      << f.output;
  // Two floors: the hand-overs alone, then lower with the processes' own running too.
  const std::size_t first = f.output.find(", at best ");
  const std::size_t second = f.output.find("with the processes' own running as measured above");
  ASSERT_NE(first, std::string::npos) << f.output;
  ASSERT_NE(second, std::string::npos) << f.output;
  const std::size_t then = f.output.find(", at best ", second);
  ASSERT_NE(then, std::string::npos) << f.output;
  const double hand_overs_only = std::strtod(f.output.c_str() + first + 10, nullptr);
  const double with_running = std::strtod(f.output.c_str() + then + 10, nullptr);
  EXPECT_GT(hand_overs_only, 0) << f.output;
  EXPECT_LE(with_running, hand_overs_only) << f.output;
  // The user-space bus's broker is a process of its own on every frame's path: its CPU time is said.
  const bool user_space = canhil::can_nodes::on_user_space_bus("vcan0");
  EXPECT_EQ(f.output.find("the bus's broker (pid ") != std::string::npos, user_space) << f.output;
  // There, a run alone asks it to look for each next frame before sleeping ([external] bus_spin_us).
  const std::size_t looked = f.output.find("it looked for a next frame ");
  EXPECT_EQ(looked != std::string::npos, user_space) << f.output;
  if (looked != std::string::npos) {
    EXPECT_GT(std::strtoull(f.output.c_str() + looked + 27, nullptr, 10), 0U) << f.output;
    EXPECT_NE(f.output.find("up to 200 us each", looked), std::string::npos) << f.output;
  }
}

}  // namespace
