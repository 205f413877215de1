// `canhil match --external` on a real vcan (the vcan suite): two teams of one
// robot, each robot's handler and agent as processes of their own under the
// time shim, started afresh for every half; the second team's with
// SECOND_RTDB=1. The same seed plays the same match twice; a robot attacks
// the goal its team attacks in each half (ends changed at half time: {x},
// {y}, {heading} and {goal_x} follow); both teams' processes drive their
// robots; a process that never attaches is named; a CAMBADA-like agent told
// its goal only through COACH_INFO (goalColor) attacks the right one on
// either side. Wall time never decides a result here: it only bounds how long
// a match may take.
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/match_test.cpp).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_paths.hpp"

namespace {

namespace fs = std::filesystem;

struct Finished {
  int status = -1;
  std::string output;  // stdout
  std::string errors;  // stderr
};

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string scratch(const std::string& name) { return "/tmp/canhil_vcan_match_" + std::to_string(getpid()) + name; }

// Runs `canhil match` to its end (at most five minutes); `environment`:
// NAME=VALUE words for it.
Finished canhil_match(const std::string& arguments, const std::string& environment = "") {
  const std::string out = scratch(".out");
  const std::string err = scratch(".err");
  const std::string command = environment + (environment.empty() ? "" : " ") + "timeout 300 " +
                              canhil::test::canhil_binary() + " match " + arguments + " > " + out + " 2> " + err;
  Finished f;
  f.status = std::system(command.c_str());
  f.output = read_file(out);
  f.errors = read_file(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return f;
}

int exit_status(const Finished& f) { return WIFEXITED(f.status) ? WEXITSTATUS(f.status) : -1; }

// One robot a team on vcan0 and vcan1; the teams' processes from [external],
// or, with `team_tables`, from each team's own [teams.external] (which then
// holds `more_external` too).
std::string write_scenario(const std::string& name, double old_x, double old_y, const std::string& agent,
                           const std::string& more_external = "", bool team_tables = false) {
  std::string path = scratch(name + ".toml");
  std::ofstream out(path);
  const std::string external = "processes = [\"canhil-hwcomm --iface {iface}\", \"" + agent + "\"]\n" + more_external;
  const std::string team_external = team_tables ? "[teams.external]\n" + external + "\n" : "";
  out << "[run]\nseed = 1\nkick_power = 40\n\n"
      << "[ball_start]\nx_m = 0.0\ny_m = 0.0\nz_m = 0.11\n\n"
      << (team_tables ? "" : "[external]\n" + external + "\n") << "[[teams]]\nname = \"new\"\nattacks = \"+x\"\n"
      << team_external << "\n"
      << "[[teams.robots]]\nx_m = -1.0\ny_m = 0.0\nheading_deg = -90.0\ninterface = \"vcan0\"\n\n"
      << "[[teams]]\nname = \"old\"\nattacks = \"-x\"\n"
      << team_external << "\n"
      << "[[teams.robots]]\nx_m = " << old_x << "\ny_m = " << old_y << "\nheading_deg = 90.0\ninterface = \"vcan1\"\n";
  return path;
}

constexpr const char* kAgent = "canhil-agent --pose {x},{y},{heading} --goal-x {goal_x}";

// The match's JSON without what the wall clock decides.
nlohmann::json without_wall_time(nlohmann::json j) {
  j.erase("wall_s");
  for (auto& m : j["matches"]) m.erase("wall_s");
  return j;
}

TEST(VcanMatch, TheTeamsProcessesPlayTheSameMatchTwiceAndScoreOnTheGoalTheyAttackInEachHalf) {
  // "new" nearer the ball: in-process it scores in each half, on +x and then on -x.
  const std::string scenario = write_scenario("goals", 3.0, 2.0, kAgent);
  const std::string run = scenario + " --external --halves 2 --half-minutes 0.15 --json --quiet";
  const Finished a = canhil_match(run);
  const Finished b = canhil_match(run);
  ASSERT_EQ(exit_status(a), 0) << a.output << a.errors;
  ASSERT_EQ(exit_status(b), 0) << b.output << b.errors;
  const nlohmann::json ja = nlohmann::json::parse(a.output);  // stdout is the JSON alone
  const nlohmann::json jb = nlohmann::json::parse(b.output);
  EXPECT_EQ(without_wall_time(ja), without_wall_time(jb)) << "one seed, one match, however the machine runs";
  const nlohmann::json& m = ja["matches"][0];
  EXPECT_DOUBLE_EQ(m["virtual_s"].get<double>(), 18.0) << "both halves played";
  ASSERT_EQ(m["goals"].size(), 2u) << ja.dump(2) << a.errors;
  for (std::size_t goal = 0; goal < 2; ++goal) {
    EXPECT_EQ(m["goals"][goal]["half"], goal + 1);
    EXPECT_EQ(m["goals"][goal]["team"], "new") << "the goal it attacks in half " << goal + 1 << " (its --goal-x)";
  }
  EXPECT_GT(m["teams"][0]["kicks"].get<int>(), 0);
  // Each half started its own processes, the second team's in its RTDB set.
  for (const char* half : {"match 1, half 1", "match 1, half 2"}) {
    EXPECT_NE(a.errors.find(half), std::string::npos) << a.errors;
  }
  EXPECT_NE(a.errors.find("canhil-agent --pose -1,0,-90 --goal-x 9` for agent 1 of team new"), std::string::npos)
      << "half 1: the placement and goal of the scenario\n"
      << a.errors;
  EXPECT_NE(a.errors.find("canhil-agent --pose 1,0,90 --goal-x -9` for agent 1 of team new"), std::string::npos)
      << "half 2: ends changed, the place turned about the centre spot and the other goal\n"
      << a.errors;
  std::remove(scenario.c_str());
}

TEST(VcanMatch, BothTeamsProcessesDriveTheirRobotsAndEachProcessWritesItsOwnLog) {
  const std::string scenario = write_scenario("kicks", 2.0, 0.0, kAgent);
  const std::string logs = scratch("_logs");
  fs::remove_all(logs);
  const Finished f = canhil_match(scenario + " --external --halves 2 --half-minutes 0.1 --json --quiet --logs " + logs);
  ASSERT_EQ(exit_status(f), 0) << f.output << f.errors;
  const nlohmann::json j = nlohmann::json::parse(f.output);
  const nlohmann::json& m = j["matches"][0];
  EXPECT_GT(m["teams"][0]["kicks"].get<int>(), 0) << j.dump(2);
  EXPECT_GT(m["teams"][1]["kicks"].get<int>(), 0) << "the second team's agent, on its own RTDB set, plays too\n"
                                                  << j.dump(2);
  EXPECT_EQ(m["teams"][0]["ftt_violations"], 0) << "canhil's nodes keep the schedule with processes in lockstep";
  EXPECT_EQ(m["teams"][1]["ftt_violations"], 0);
  for (const char* half : {"half1", "half2"}) {
    for (const char* team : {"new", "old"}) {
      const std::string base = logs + "/match1-" + half + "-" + team + "-agent1-";
      const std::string agent_log = read_file(base + "canhil-agent.log");
      EXPECT_NE(agent_log.find("canhil-agent: agent 1"), std::string::npos) << base << "canhil-agent.log";
      EXPECT_TRUE(fs::exists(base + "canhil-hwcomm.log")) << base;
    }
  }
  EXPECT_NE(read_file(logs + "/match1-half1-old-agent1-canhil-agent.log").find("opponent goal at x = -9.00"),
            std::string::npos)
      << "the second team attacks -x in the first half";
  EXPECT_NE(read_file(logs + "/match1-half2-old-agent1-canhil-agent.log").find("opponent goal at x = 9.00"),
            std::string::npos)
      << "and +x in the second";
  fs::remove_all(logs);
  std::remove(scenario.c_str());
}

// Each record's lines, without what the wall clock decides.
std::vector<nlohmann::json> records_without_wall_time(const std::string& path) {
  std::vector<nlohmann::json> records;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    nlohmann::json r = nlohmann::json::parse(line);
    r.erase("wall_s");
    records.push_back(r);
  }
  return records;
}

TEST(VcanMatch, TwoAtATimeEachOnABusAndAnIpcNamespaceOfItsOwnGiveTheRecordsOfOneAtATime) {
  // A noisy camera: each seed plays a match of its own.
  const std::string scenario = write_scenario("jobs", 3.0, 2.0, kAgent);
  std::ofstream(scenario, std::ios::app) << "\n[vision]\npoint_noise_m = 0.02\nball_noise_m = 0.05\n";
  const std::string one = scratch("_one.jsonl");
  const std::string two = scratch("_two.jsonl");
  std::remove(one.c_str());
  std::remove(two.c_str());
  const std::string run = scenario + " --external --halves 1 --half-minutes 0.1 --seeds 1..3 --json --quiet";
  // A killed worker's bus folder (its pid gone) is removed; a running one's is not.
  const fs::path bus = std::getenv("CANHIL_BUS_DIR") != nullptr ? std::getenv("CANHIL_BUS_DIR") : "/tmp/none";
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  waitpid(gone, nullptr, 0);
  const fs::path orphan = bus.string() + "-worker-" + std::to_string(gone);
  const fs::path alive = bus.string() + "-worker-" + std::to_string(getpid());
  fs::create_directories(orphan);
  fs::create_directories(alive);
  const Finished a = canhil_match(run + " --jobs 1 --records " + one);
  const Finished b = canhil_match(run + " --jobs 2 --records " + two);
  EXPECT_FALSE(fs::exists(orphan)) << "a killed worker's bus folder is removed by the next batch";
  EXPECT_TRUE(fs::exists(alive)) << "a running worker's is left alone";
  fs::remove(alive);
  ASSERT_EQ(exit_status(a), 0) << a.output << a.errors;
  ASSERT_EQ(exit_status(b), 0) << b.output << b.errors;
  const std::vector<nlohmann::json> sequential = records_without_wall_time(one);
  ASSERT_EQ(sequential.size(), 3u);
  EXPECT_EQ(records_without_wall_time(two), sequential) << "the same matches, trace hashes included";
  EXPECT_NE(sequential[0]["trace_hash"], sequential[1]["trace_hash"]) << "the seeds played matches of their own";
  EXPECT_EQ(without_wall_time(nlohmann::json::parse(b.output)), without_wall_time(nlohmann::json::parse(a.output)));
  // Two workers, each on its own bus and in its own IPC namespace, none of them this test's.
  std::error_code unread;
  const std::string own = fs::read_symlink("/proc/self/ns/ipc", unread).string();
  std::vector<std::string> spaces;
  for (std::size_t at = b.errors.find("IPC namespace of its own ("); at != std::string::npos;
       at = b.errors.find("IPC namespace of its own (", at + 1)) {
    const std::size_t from = at + 26;
    spaces.push_back(b.errors.substr(from, b.errors.find_first_of(",)", from) - from));
  }
  ASSERT_EQ(spaces.size(), 2u) << b.errors;
  EXPECT_NE(spaces[0], spaces[1]) << b.errors;
  for (const std::string& s : spaces) EXPECT_NE(s, own) << b.errors;
  EXPECT_EQ(a.errors.find("a worker (pid"), std::string::npos) << "one at a time: the batch's own bus\n" << a.errors;
  // The workers' buses are gone with them.
  for (const auto& entry : fs::directory_iterator(bus.parent_path())) {
    EXPECT_EQ(entry.path().filename().string().rfind(bus.filename().string() + "-worker-", 0), std::string::npos)
        << entry.path();
  }
  std::remove(one.c_str());
  std::remove(two.c_str());
  std::remove(scenario.c_str());
}

// The parent pid of process `pid` (/proc/PID/status), or -1 when it is gone.
long parent_of(long pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("PPid:", 0) == 0) return std::strtol(line.c_str() + 5, nullptr, 10);
  }
  return -1;
}

// Every number that follows `marker` in `text`.
std::vector<long> numbers_after(const std::string& text, const std::string& marker) {
  std::vector<long> found;
  for (std::size_t at = text.find(marker); at != std::string::npos; at = text.find(marker, at + 1)) {
    found.push_back(std::strtol(text.c_str() + at + marker.size(), nullptr, 10));
  }
  return found;
}

TEST(VcanMatch, AWorkerKilledInAMatchTakesItsProcessesWithItAndTheBatchGoesOn) {
  const std::string scenario = write_scenario("killed", 3.0, 2.0, kAgent);
  const std::string records = scratch("_killed.jsonl");
  const std::string err = scratch("_killed.err");
  std::remove(records.c_str());
  const pid_t batch = fork();
  ASSERT_GE(batch, 0);
  if (batch == 0) {
    const std::string command = "exec timeout 300 " + canhil::test::canhil_binary() + " match " + scenario +
                                " --external --jobs 2 --seeds 1..3 --halves 1 --half-minutes 0.5 --quiet --records " +
                                records + " > /dev/null 2> " + err;
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wall time only bounds the waits: a worker with its four processes started
  // (each team's handler and agent).
  long worker = -1;
  std::vector<long> its;
  for (int k = 0; k < 600 && its.size() < 4; ++k) {
    usleep(50'000);
    const std::string text = read_file(err);
    const std::vector<long> workers = numbers_after(text, "a worker (pid ");
    if (workers.empty()) continue;
    worker = workers[0];
    its.clear();
    for (const long p : numbers_after(text, "(pid ")) {
      if (p != worker && parent_of(p) == worker) its.push_back(p);
    }
  }
  ASSERT_EQ(its.size(), 4u) << read_file(err);
  ASSERT_EQ(kill(static_cast<pid_t>(worker), SIGKILL), 0);
  const auto any_left = [&] {
    for (const long p : its) {
      if (parent_of(p) >= 0) return true;
    }
    return false;
  };
  for (int k = 0; k < 100 && any_left(); ++k) usleep(50'000);
  EXPECT_FALSE(any_left()) << "the killed worker's handlers and agents ended with it";
  int status = 0;
  ASSERT_EQ(waitpid(batch, &status, 0), batch);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1) << "a failed match: the batch's CI sees it\n" << read_file(err);
  std::ifstream in(records);
  int played = 0;
  int failed = 0;
  for (std::string line; std::getline(in, line);) {
    const nlohmann::json r = nlohmann::json::parse(line);
    if (r["failed"].is_null()) {
      ++played;
    } else {
      ++failed;
      EXPECT_NE(r["failed"].get<std::string>().find("killed by signal 9"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(failed, 1);
  EXPECT_EQ(played, 2) << "the other matches were played: the batch went on";
  std::remove(records.c_str());
  std::remove(err.c_str());
  std::remove(scenario.c_str());
}

TEST(VcanMatch, AWorkerThatCannotMakeItsBusStopsTheBatchSayingWhy) {
  // A bus folder of 95 characters: the batch's own would fit a socket's path,
  // a worker's (`-worker-<pid>` more) cannot.
  std::string folder = "/tmp/canhil-long-";
  folder += std::string(95 - folder.size(), 'x');
  const std::string scenario = write_scenario("nobus", 3.0, 2.0, kAgent);
  const Finished g =
      canhil_match(scenario + " --external --jobs 2 --seeds 1..2 --half-minutes 0.1 --no-records --quiet",
                   "CANHIL_BUS_DIR=" + folder);
  EXPECT_EQ(exit_status(g), 2) << g.output << g.errors;
  EXPECT_NE(g.errors.find("a match worker's own bus: the bus folder " + folder + "-worker-"), std::string::npos)
      << g.errors;
  EXPECT_NE(g.errors.find("too long for a socket's path"), std::string::npos) << g.errors;
  EXPECT_EQ(g.errors.find("usage:"), std::string::npos) << "the machine's matter, not the command line's\n" << g.errors;
  EXPECT_EQ(g.errors.find("started `"), std::string::npos) << "nothing started\n" << g.errors;
  std::remove(scenario.c_str());
}

TEST(VcanMatch, AProcessThatNeverAnswersStopsTheMatchNamingItsMatchAndHalf) {
  // The agent's process drops the lockstep's board before its program starts:
  // canhil never hears from it again, and says so after the attach limit.
  // The limit is the teams' own ([teams.external]; [external]'s is 60 s).
  const std::string scenario =
      write_scenario("stuck", 3.0, 2.0, "env -u CANHIL_LOCKSTEP GOAL_X={goal_x} sleep 30", "attach_limit_s = 3", true);
  const Finished f = canhil_match(scenario + " --external --half-minutes 0.1 --quiet --json");
  EXPECT_EQ(exit_status(f), 3) << f.output << f.errors;
  EXPECT_NE(f.errors.find("canhil match: stopped: match 1, half 1"), std::string::npos) << f.errors;
  EXPECT_NE(f.errors.find("within 3.000 s of wall time"), std::string::npos) << "the teams' attach_limit_s\n"
                                                                             << f.errors;
  const nlohmann::json j = nlohmann::json::parse(f.output);  // what was played before: nothing, said so
  EXPECT_TRUE(j["stopped"].get<bool>());
  EXPECT_TRUE(j["matches"].empty());
  std::remove(scenario.c_str());
}

TEST(VcanMatch, AProgramThatIsNotFoundStopsTheMatchSayingSo) {
  const std::string scenario = write_scenario("typo", 3.0, 2.0, "canhil-agnet --goal-x {goal_x}");
  const Finished f = canhil_match(scenario + " --external --half-minutes 0.1 --quiet --json");
  EXPECT_EQ(exit_status(f), 3) << f.output << f.errors;
  EXPECT_NE(f.errors.find("canhil match: stopped: match 1, half 1 at t = "), std::string::npos) << f.errors;
  EXPECT_NE(f.errors.find("never ran: the shell found no such program (exit status 127)"), std::string::npos)
      << f.errors;
  EXPECT_TRUE(nlohmann::json::parse(f.output)["stopped"].get<bool>());
  std::remove(scenario.c_str());
}

// Both teams the CAMBADA-like agent (tests/laptop/team_agent.cpp --attack),
// relinked against canhil's librtdb.so as a team relinks its agent for the
// second team (SECOND_RTDB), with its handler in CAMBADA's layout: neither is
// given {goal_x}, so each learns its goal only as CAMBADA's agent does, from
// COACH_INFO's goalColor and the compass. The first team's robot is parked
// (running = false); the second team's starts on the -x side of the ball: told
// right, it goes round the ball and scores in -x; told wrong (goalColor
// Yellow, as before the layout mapped `attacks`), it would kick from where it
// stands towards +x.
std::string write_cambada_like(const std::string& name) {
  const std::string team = canhil::test::source_dir() + "/tests/support/cambada_like/";
  const std::string libs = std::string("--rtdb-lib ") + CANHIL_TEST_LIBRTDB + " --rtdb-items " + team +
                           "rtdb_user.h --rtdb-ini " + team + "config/rtdb.ini --layout cambada";
  const std::string laptop = std::string("[teams.laptop]\nrtdb_lib = \"") + CANHIL_TEST_LIBRTDB +
                             "\"\nrtdb_items = \"" + team + "rtdb_user.h\"\nrtdb_ini = \"" + team +
                             "config/rtdb.ini\"\nlayout = \"cambada\"\npman = \"builtin\"\n";
  const std::string external = "[teams.external]\nprocesses = [\"canhil-hwcomm --iface {iface} " + libs + "\", \"" +
                               CANHIL_TEST_TEAM_AGENT_RELINKED + " --ini " + team +
                               "config/rtdb.ini --attack\"]\nattach_limit_s = 60\nanswer_limit_s = 10\n";
  std::string path = scratch(name + ".toml");
  std::ofstream out(path);
  out << "[run]\nseed = 2\nkick_power = 40\n\n"
      << "[ball_start]\nx_m = 0.0\ny_m = 0.0\nz_m = 0.11\n\n"
      << "[[teams]]\nname = \"first\"\nattacks = \"+x\"\n"
      << laptop << external << "\n"
      << "[[teams.robots]]\nx_m = 6.0\ny_m = 4.0\nheading_deg = 90.0\ninterface = \"vcan0\"\nrunning = false\n\n"
      << "[[teams]]\nname = \"second\"\nattacks = \"-x\"\n"
      << laptop << external << "\n"
      << "[[teams.robots]]\nx_m = -1.2\ny_m = 0.3\nheading_deg = -60.0\ninterface = \"vcan1\"\n";
  return path;
}

TEST(VcanMatch, ACambadaLikeAgentToldItsGoalByTheCoachAttacksMinusXForTheSecondTeam) {
  const std::string scenario = write_cambada_like("cambada");
  const std::string logs = scratch("_cambada_logs");
  fs::remove_all(logs);
  const Finished f =
      canhil_match(scenario + " --external --halves 1 --half-minutes 0.15 --json --quiet --logs " + logs);
  ASSERT_EQ(exit_status(f), 0) << f.output << f.errors;
  const nlohmann::json j = nlohmann::json::parse(f.output);
  const nlohmann::json& m = j["matches"][0];
  ASSERT_GE(m["goals"].size(), 1u) << j.dump(2) << f.errors;
  EXPECT_EQ(m["goals"][0]["team"], "second") << "in the -x goal, the one the second team attacks\n" << j.dump(2);
  EXPECT_GT(m["teams"][1]["kicks"].get<int>(), 0) << j.dump(2);
  EXPECT_GT(m["referee_calls"].get<int>(), 0) << "the goal's kick-off at least\n" << j.dump(2);
  const std::string program = fs::path(CANHIL_TEST_TEAM_AGENT_RELINKED).filename().string();
  const std::string first = read_file(logs + "/match1-half1-first-agent1-" + program + ".log");
  const std::string second = read_file(logs + "/match1-half1-second-agent1-" + program + ".log");
  EXPECT_NE(first.find("goalColor Yellow"), std::string::npos) << first;
  EXPECT_NE(second.find("goalColor Blue: the compass turned by 180 degrees"), std::string::npos) << second;
  // Woken only once their clocks read the frame's instant: the clock never
  // moves under a running cycle (it did when PMan's tick went out in the step).
  for (const std::string* log : {&first, &second}) {
    const auto at = log->rfind("clock moved in ");
    ASSERT_NE(at, std::string::npos) << *log;
    EXPECT_EQ(std::strtol(log->c_str() + at + 15, nullptr, 10), 0) << *log;
  }
  fs::remove_all(logs);

  // canhil run --external prints the referee's calls as they come and in the
  // summary, and the world log carries them.
  const std::string log = scratch("_cambada_world.csv");
  const std::string out = scratch("_cambada_run.out");
  const int status = std::system(("timeout 300 " + canhil::test::canhil_binary() + " run --config " + scenario +
                                  " --external --duration 9 --world-log " + log + " > " + out + " 2>&1")
                                     .c_str());
  const std::string run = read_file(out);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << run;
  EXPECT_NE(run.find("GOAL at "), std::string::npos) << run;
  EXPECT_NE(run.find("in the -x goal, for second"), std::string::npos) << run;
  EXPECT_NE(run.find("referee: goal for second in the -x goal (0:1)"), std::string::npos) << "as it came\n" << run;
  EXPECT_NE(run.find("score first 0 : second 1"), std::string::npos) << run;
  EXPECT_NE(read_file(log).find("#referee"), std::string::npos);
  std::remove(log.c_str());
  std::remove(out.c_str());
  std::remove(scenario.c_str());
}

}  // namespace
