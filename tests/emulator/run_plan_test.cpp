// A run's plan: the scenario file's values where the command line says
// nothing, each override where it does (one test per field), every default
// filled in and every team's laptop side resolved once, and the mistakes of
// each named (the file's by file and line, an override's by its option).
#include "canhil/emulator/run_plan.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "canhil/frames/messages.hpp"
#include "support/counter_watch.hpp"
#include "support/error_of.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class RunPlanTest : public test::WatchedTest {
 protected:
  void SetUp() override {
    std::ofstream(file_) << "[run]\nduration_s = 7\nseed = 5\nkick_power = 30\nfaults = [\"drop:M4_1:0.5\"]\n"
                            "[external]\nprocesses = [\"agent {agent}\"]\nanswer_limit_s = 2\n"
                            "[laptop]\nlayout = \"canhil\"\n";
  }
  void TearDown() override { std::filesystem::remove(file_); }
  RunPlan plan(const RunOverrides& o = {}) {
    SessionOptions options;
    options.messages = frames::MessageSet::load(test::shipped_dbc());
    return plan_run(file_, o, options);
  }
  std::filesystem::path file_ =
      std::filesystem::temp_directory_path() / ("canhil-plan-" + std::to_string(getpid()) + ".toml");
};

TEST_F(RunPlanTest, WithoutOverridesTheFilesValuesAndCanhilsDefaults) {
  const RunPlan p = plan();
  EXPECT_EQ(p.source, file_);
  EXPECT_EQ(p.mode(), RunMode::kVirtual);
  EXPECT_FALSE(p.options.realtime);
  EXPECT_FALSE(p.options.external);
  EXPECT_EQ(p.scenario.seed, 5u);
  EXPECT_EQ(p.scenario.kick_power, 30);
  EXPECT_EQ(p.scenario.faults.size(), 1u);
  EXPECT_DOUBLE_EQ(p.length.seconds, 7.0);
  EXPECT_EQ(p.length.source, "the scenario's duration_s");
  EXPECT_EQ(p.scenario.external.answer_limit_s, 2.0);
  ASSERT_EQ(p.scenario.interfaces.size(), 1u) << "complete: one robot, placed by default";
  EXPECT_EQ(p.scenario.interfaces[0], "vcan0");
  ASSERT_EQ(p.laptops.size(), 1u);
  EXPECT_EQ(p.laptops[0].rtdb_lib, "builtin") << "resolved";
  EXPECT_EQ(p.laptops[0].layout, "canhil");
  EXPECT_EQ(p.laptops[0].pman, "none") << "virtual time: no PMan unless asked";
  EXPECT_EQ(p.scenario.laptop.rtdb_lib, "builtin") << "the scenario read later says what the run uses";
}

TEST_F(RunPlanTest, TheModeSetsTheOptionsAndTheLaptopsDefaults) {
  RunOverrides o;
  o.mode = RunMode::kRealtime;
  RunPlan p = plan(o);
  EXPECT_EQ(p.mode(), RunMode::kRealtime);
  EXPECT_TRUE(p.options.realtime);
  EXPECT_EQ(p.laptops[0].pman, "builtin") << "real time: canhil's PMan";
  o.mode = RunMode::kExternal;
  p = plan(o);
  EXPECT_EQ(p.mode(), RunMode::kExternal);
  EXPECT_TRUE(p.options.external);
  EXPECT_FALSE(p.options.realtime);
  EXPECT_EQ(p.laptops[0].pman, "builtin");
}

TEST_F(RunPlanTest, Seed) {
  RunOverrides o;
  o.seed = 42;
  EXPECT_EQ(plan(o).scenario.seed, 42u);
}

TEST_F(RunPlanTest, KickPower) {
  RunOverrides o;
  o.kick_power = 77;
  EXPECT_EQ(plan(o).scenario.kick_power, 77);
}

TEST_F(RunPlanTest, TheBusTakesBitRateOverTheBusTableOverTheDbcsBaudrate) {
  const RunPlan dbc = plan();
  EXPECT_EQ(dbc.options.bus.bit_rate, 1'000'000u) << "the shipped DBC's BA_ \"Baudrate\" 1000000";
  EXPECT_STREQ(dbc.options.bus.source(), "the DBC's Baudrate");
  EXPECT_EQ(dbc.options.ftt.bit_rate, 1'000'000u) << "the schedule's wire times at the wire's rate";
  EXPECT_EQ(dbc.options.ftt.stamps, frames::StampAt::kEndOfFrame) << "canhil's wire stamps the end of frame";
  EXPECT_EQ(dbc.options.bus.restart, std::optional<Nanos>(100ms)) << "restart-ms 100 unless [bus] says";
  EXPECT_EQ(dbc.options.bus.tx_queue, 10u) << "can-dev's txqueuelen";
  EXPECT_EQ(describe_bus(dbc.options.bus),
            "each robot's bus on a timed wire at 1000 kbit/s (the DBC's Baudrate; --bit-rate 0: instant)");
  RunOverrides o;
  o.bit_rate = 500'000;
  const RunPlan timed = plan(o);
  EXPECT_EQ(timed.options.bus.bit_rate, 500'000u);
  EXPECT_EQ(timed.options.ftt.bit_rate, 500'000u);
  EXPECT_STREQ(timed.options.bus.source(), "--bit-rate");
  std::ofstream(file_) << "[bus]\nbit_rate = 250000\nrestart_ms = 0\ntx_queue = 32\n";
  const RunPlan file = plan();
  EXPECT_EQ(file.options.bus.bit_rate, 250'000u);
  EXPECT_STREQ(file.options.bus.source(), "the scenario's [bus] bit_rate");
  EXPECT_EQ(file.options.bus.restart, std::nullopt) << "0: bus-off until restarted";
  EXPECT_EQ(file.options.bus.tx_queue, 32u);
  o.bit_rate = 0;
  const RunPlan instant = plan(o);
  EXPECT_FALSE(instant.options.bus.timed()) << "--bit-rate 0 over the file: instant";
  EXPECT_EQ(instant.options.ftt.stamps, frames::StampAt::kStartOfFrame);
  EXPECT_EQ(describe_bus(instant.options.bus),
            "instant buses (--bit-rate 0): every frame at once, no wire time, arbitration or errors (--bit-rate B: "
            "a timed wire)");
  o.bit_rate = 1'000'000;
  o.mode = RunMode::kRealtime;
  EXPECT_EQ(plan(o).options.ftt.stamps, frames::StampAt::kEndOfFrame)
      << "in real time too: the user-space bus's wire and a real adapter stamp the end of frame";
  // On SocketCAN (real time, the team's processes) the DBC's Baudrate alone
  // times nothing: the kernel's vcan cannot carry the wire the user-space bus
  // can, and one command gives one run on every machine.
  std::ofstream(file_) << "[run]\nduration_s = 7\n";
  for (const RunMode mode : {RunMode::kRealtime, RunMode::kExternal}) {
    RunOverrides socketcan;
    socketcan.mode = mode;
    const RunPlan p = plan(socketcan);
    EXPECT_FALSE(p.options.bus.timed());
    EXPECT_STREQ(p.options.bus.source(), "on SocketCAN the DBC's Baudrate alone times nothing");
    EXPECT_EQ(p.options.ftt.stamps, frames::StampAt::kStartOfFrame);
  }
  for (const double bad : {5.0, 2e6, 125000.5, -1.0}) {
    o.bit_rate = bad;
    EXPECT_EQ(test::error_of([&] { plan(o); }),
              "--bit-rate takes 10000..1000000 bit/s, or 0 for an instant bus (no wire time, no errors)")
        << bad;
  }
}

TEST_F(RunPlanTest, AMessageSetWithoutABaudrateRunsOnInstantBuses) {
  std::string text;
  {
    std::ifstream in(test::shipped_dbc());
    std::ostringstream all;
    all << in.rdbuf();
    text = all.str();
  }
  // The shipped DBC without its Baudrate attribute (definition, default, value).
  std::istringstream lines(text);
  std::string line, kept;
  while (std::getline(lines, line)) {
    if (line.find("\"Baudrate\"") == std::string::npos) kept += line + "\n";
  }
  ASSERT_NE(kept.size(), text.size());
  SessionOptions options;
  options.messages = frames::MessageSet::create(frames::parse_dbc(kept, "no-baudrate.dbc"));
  const RunPlan p = plan_run(file_, {}, options);
  EXPECT_FALSE(p.options.bus.timed());
  EXPECT_STREQ(p.options.bus.source(), "no Baudrate in the DBC");
  EXPECT_NE(describe_bus(p.options.bus).find("instant buses (no Baudrate in the DBC)"), std::string::npos);
}

TEST_F(RunPlanTest, Duration) {
  RunOverrides o;
  o.duration_s = 3;
  const RunPlan p = plan(o);
  EXPECT_DOUBLE_EQ(p.length.seconds, 3.0);
  EXPECT_EQ(p.length.source, "--duration");
  o.duration_s = 0;
  EXPECT_EQ(test::error_of([&] { plan(o); }), "--duration takes seconds above 0") << "in virtual time";
  o.mode = RunMode::kRealtime;
  EXPECT_EQ(plan(o).length.seconds, 0.0) << "in real time 0 is until stopped";
}

TEST_F(RunPlanTest, FaultsAddToTheFiles) {
  RunOverrides o;
  o.faults = {"silence:Motor2:6"};
  EXPECT_EQ(plan(o).scenario.faults.size(), 2u);
  o.faults = {"nonsense"};
  try {
    plan(o);
    ADD_FAILURE() << "a fault that does not read";
  } catch (const OverrideError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("--fault: ", 0), 0u) << e.what();
  }
}

TEST_F(RunPlanTest, ProcessesReplaceTheFiles) {
  RunOverrides o;
  o.processes = {"handler {iface}", "agent {agent}"};
  EXPECT_EQ(plan(o).scenario.external.processes, o.processes);
}

TEST_F(RunPlanTest, AnswerLimitIsEveryTeams) {
  RunOverrides o;
  o.answer_limit_s = 0.5;
  EXPECT_EQ(plan(o).scenario.external.answer_limit_s, 0.5);
  o.answer_limit_s = 0.001;
  EXPECT_EQ(test::error_of([&] { plan(o); }), "--answer-limit takes 0.01..3600 s");
}

TEST_F(RunPlanTest, AnExternalRunsProcessesAreEachRobotsLinesExpandedAndItsLimitsTheLongestAnyTeamGives) {
  std::ofstream(file_)
      << "[[teams]]\nname = \"a\"\n"
         "[[teams.robots]]\nx_m = -1.0\ny_m = 2.0\nheading_deg = 90.0\n"
         "[teams.external]\nprocesses = [\"handler --iface {iface}\", \"agent {agent} {x},{y},{heading} {goal_x}\"]\n"
         "answer_limit_s = 2\nattach_limit_s = 5\nsyslog = \"system\"\n"
         "[[teams]]\nname = \"b\"\n"
         "[[teams.robots]]\nx_m = 3.0\ny_m = -0.5\nheading_deg = 0.0\n"
         "[teams.external]\nprocesses = [\"theirs {agent} {goal_x}\"]\nanswer_limit_s = 3\nbusy_limit_s = 9\n";
  RunOverrides o;
  o.mode = RunMode::kExternal;
  const RunPlan p = plan(o);
  const ExternalPlan& e = p.external;
  ASSERT_EQ(e.launches.size(), 3u);
  EXPECT_EQ(e.launches[0].command, "handler --iface vcan0");
  EXPECT_EQ(e.launches[1].command, "agent 1 -1,2,90 9");
  EXPECT_EQ(e.launches[1].syslog, "system");
  EXPECT_EQ(e.launches[2].command, "theirs 1 -9") << "the second team attacks -x";
  EXPECT_EQ(e.launches[2].team, 1u);
  EXPECT_EQ(e.launches[2].robot, 1u);
  EXPECT_EQ(e.launches[2].syslog, "log");
  EXPECT_EQ(e.conductor.answer_limit, from_seconds(3)) << "the longest: one virtual clock for all";
  EXPECT_EQ(e.conductor.busy_limit, from_seconds(60)) << "team a's default is longer than b's 9 s";
  EXPECT_EQ(e.attach_limit_s, 60) << "team b's default is longer than a's 5 s";
  EXPECT_TRUE(plan().external.launches.empty()) << "a run without --external resolves no processes";
}

TEST_F(RunPlanTest, ACommandsOwnOverridesArePlannedAndTheScenarioItHoldsStaysAsLoaded) {
  Scenario three;  // one team of three
  three.world.robots = {{-1, 0, 0}, {-2, 1, 0}, {-2, -1, 0}};
  SessionOptions options;
  options.messages = frames::MessageSet::load(test::shipped_dbc());
  RunOverrides one;  // canhil nodes: one robot on one interface
  one.robots = 1;
  one.interfaces = {"can3"};
  one.agents = {4};
  one.seed = 77;
  const RunPlan p = plan_run(three, options, one);
  EXPECT_EQ(p.scenario.robot_count(), 1u);
  EXPECT_EQ(p.scenario.interfaces, std::vector<std::string>{"can3"});
  EXPECT_EQ(p.scenario.agents, std::vector<int>{4});
  EXPECT_EQ(p.scenario.seed, 77u);
  EXPECT_EQ(three.world.robots.size(), 3u) << "the scenario a command holds is not changed";
  EXPECT_TRUE(three.interfaces.empty()) << "nor completed";

  const Scenario loaded = read_scenario(shipped_scenario("two_teams.toml"));

  RunOverrides second_half;  // a match's second half: the ends changed
  second_half.half = 1;
  second_half.duration_s = 30;
  const RunPlan h = plan_run(loaded, options, second_half);
  const RunPlan first = plan_run(loaded, options);
  EXPECT_EQ(h.scenario.world.robots.at(0).x_m, -first.scenario.world.robots.at(0).x_m);
  EXPECT_NE(h.scenario.teams.at(0).attacks_positive_x, first.scenario.teams.at(0).attacks_positive_x);
  EXPECT_EQ(h.length.seconds, 30);
}

TEST_F(RunPlanTest, Layout) {
  RunOverrides o;
  o.layout = "cambada";
  EXPECT_EQ(plan(o).laptops[0].layout, "cambada");
}

TEST_F(RunPlanTest, Pman) {
  RunOverrides o;
  o.pman = "builtin";
  EXPECT_EQ(plan(o).laptops[0].pman, "builtin");
}

TEST_F(RunPlanTest, RtdbLibItemsAndIniAreResolvedTogetherAndTheFileIsNamed) {
  RunOverrides o;
  o.rtdb_lib = "/opt/team/librtdb.so";
  const std::string e = test::error_of([&] { plan(o); });
  EXPECT_EQ(e.rfind(file_.string() + ": the team RTDB library /opt/team/librtdb.so needs its item table", 0), 0u) << e;
  o.rtdb_lib.reset();
  o.rtdb_items = "rtdb_user.h";
  EXPECT_NE(test::error_of([&] { plan(o); }).find("give that library too"), std::string::npos);
  o.rtdb_items.reset();
  o.rtdb_ini = "rtdb.ini";
  EXPECT_NE(test::error_of([&] { plan(o); }).find("give that library too"), std::string::npos);
}

TEST_F(RunPlanTest, AMistakeInTheFileIsNamedByFileAndLine) {
  std::ofstream(file_) << "[run]\nseed = \"five\"\n";
  const std::string e = test::error_of([&] { plan(); });
  EXPECT_NE(e.find(file_.string()), std::string::npos) << e;
  EXPECT_NE(e.find("seed"), std::string::npos) << e;
}

TEST_F(RunPlanTest, APlanBuiltInCodeIsCompletedAndNeedsAMessageSet) {
  SessionOptions options;
  EXPECT_EQ(test::error_of([&] { plan_run(Scenario{}, options); }), "a run needs a message set");
  options.messages = frames::MessageSet::load(test::shipped_dbc());
  const RunPlan p = plan_run(Scenario{}, options);
  EXPECT_TRUE(p.source.empty());
  EXPECT_EQ(p.scenario.robot_count(), 1u);
  EXPECT_EQ(p.length.source, "the default: no duration_s in the scenario");
}

}  // namespace
}  // namespace canhil::emulator
