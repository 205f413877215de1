// Scenarios: the [run] table's fields and mistakes, the defaults and rules
// complete() fills in and checks for every scenario, and the shipped ones.
#include "canhil/emulator/scenario.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"
#include "canhil/physics/config.hpp"
#include "canhil/physics/field.hpp"
#include "support/error_of.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

// What a scenario text's mistake says.
std::string error_of(const std::string& text) {
  return test::error_of<physics::ConfigError>([&] { parse_scenario(text, "bad.toml"); });
}

TEST(Scenarios, FileMistakesNameTheFileTheFieldAndWhatToDo) {
  const std::string robot = "[[robots]]\nx_m = 0\n";
  EXPECT_NE(
      error_of(robot + "[run]\ninterfaces = [\"vcan0\", \"vcan1\"]\n").find("bad.toml:4: run.interfaces: give one"),
      std::string::npos)
      << error_of(robot + "[run]\ninterfaces = [\"vcan0\", \"vcan1\"]\n");
  EXPECT_NE(error_of("[run]\nfaults = [\"drop:M1:7\"]\n").find("run.faults: fault 'drop:M1:7'"), std::string::npos);
  EXPECT_NE(error_of("[run]\nduratoin_s = 3\n").find("run.duratoin_s: unknown field"), std::string::npos);
  EXPECT_NE(error_of(robot + robot + "[run]\nagents = [2, 2]\n").find("appears twice"), std::string::npos);
  EXPECT_NE(error_of("[rnu]\n").find("unknown field"), std::string::npos) << "the world's own check";
  EXPECT_NE(error_of("[bus]\nbit_rate = 2000000\n").find("bad.toml:2: bus.bit_rate: must be a number from 0 to 1e+06"),
            std::string::npos)
      << error_of("[bus]\nbit_rate = 2000000\n");
  EXPECT_NE(error_of("[bus]\nbitrate = 1\n").find("bus.bitrate: unknown field; known here: bit_rate"),
            std::string::npos);
  EXPECT_NE(error_of("[firmware]\nwatchdog_ms = 0\n").find("bad.toml:2: firmware.watchdog_ms: must be a number from 1"),
            std::string::npos)
      << error_of("[firmware]\nwatchdog_ms = 0\n");
  EXPECT_EQ(parse_scenario("[firmware]\nwatchdog_ms = 400\n", "fw.toml").firmware.watchdog_ms, 400.0);
  EXPECT_FALSE(parse_scenario("", "none.toml").firmware.watchdog_ms) << "unset: the nodes' default";
  const Scenario ok = parse_scenario(robot + robot + "[run]\nseed = 9\nagents = [3, 1]\n", "ok.toml");
  EXPECT_EQ(ok.seed, 9u);
  EXPECT_EQ(ok.agents, (std::vector<int>{3, 1}));
  EXPECT_EQ(ok.interfaces, (std::vector<std::string>{"vcan0", "vcan1"}));
  const Scenario one = load_scenario(test::source_dir() + "/emulator/scenarios/one_robot.toml");
  EXPECT_EQ(one.world.robots.size(), 1u);
  EXPECT_DOUBLE_EQ(one.duration_s, 8);
}

TEST(Scenarios, TheCambadaFieldIsTheOneCambadasConfigurationDescribes) {
  // cambada-pub's config/cambada.conf.xml, in millimetres there: field_length
  // 17875, field_width 11375, center_circle_radius 1875, goal_area 625 x 3375,
  // penalty_area 2125 x 6375, corner_arc_radius 625, goal 2000 wide, 500 deep.
  const Scenario s = load_scenario(test::source_dir() + "/emulator/scenarios/cambada_field.toml");
  const physics::FieldParams& f = s.world.field;
  EXPECT_DOUBLE_EQ(f.length_m, 17.875);
  EXPECT_DOUBLE_EQ(f.width_m, 11.375);
  EXPECT_DOUBLE_EQ(f.centre_circle_radius_m, 1.875);
  EXPECT_DOUBLE_EQ(f.goal_area_depth_m, 0.625);
  EXPECT_DOUBLE_EQ(f.goal_area_width_m, 3.375);
  EXPECT_DOUBLE_EQ(f.penalty_area_depth_m, 2.125);
  EXPECT_DOUBLE_EQ(f.penalty_area_width_m, 6.375);
  EXPECT_DOUBLE_EQ(f.corner_arc_radius_m, 0.625);
  EXPECT_DOUBLE_EQ(f.goal.width_m, 2.0);
  EXPECT_DOUBLE_EQ(f.goal.depth_m, 0.5);
  // Its lines where CAMBADA's localisation draws them (their centres).
  const physics::FieldMarkings m = physics::field_markings(f);
  EXPECT_NEAR(m.distance_to_nearest(17.875 / 2, 2.0), 0.0, 1e-12) << "a goal line";
  EXPECT_NEAR(m.distance_to_nearest(1.0, 11.375 / 2), 0.0, 1e-12) << "a touch line";
  EXPECT_NEAR(m.distance_to_nearest(9.0, 2.0), 0.0625, 1e-12) << "canhil's default goal line is off it";
  ASSERT_EQ(s.teams.size(), 2u);
  EXPECT_FALSE(s.teams[1].attacks_positive_x);
}

TEST(Scenarios, ARunLastsTheFlagsTimeElseTheScenariosElseTwentySecondsOrUntilCtrlCInRealTime) {
  const Scenario given = parse_scenario("[run]\nduration_s = 60\n", "given.toml");
  const Scenario silent = parse_scenario("[run]\nseed = 2\n", "silent.toml");
  for (const bool realtime : {false, true}) {
    const RunLength flag = given.run_length(5.0, realtime);
    EXPECT_EQ(flag.seconds, 5.0);
    EXPECT_EQ(flag.source, "--duration");
    const RunLength file = given.run_length(std::nullopt, realtime);
    EXPECT_EQ(file.seconds, 60.0) << "the scenario's value holds in real time too";
    EXPECT_EQ(file.source, "the scenario's duration_s");
    EXPECT_THROW(given.run_length(-1.0, realtime), SetupError);
  }
  const RunLength virtual_default = silent.run_length(std::nullopt, false);
  EXPECT_EQ(virtual_default.seconds, 20.0);
  EXPECT_EQ(virtual_default.source, "the default: no duration_s in the scenario");
  const RunLength open_ended = silent.run_length(std::nullopt, true);
  EXPECT_EQ(open_ended.seconds, 0.0) << "no value and no flag: until Ctrl-C";
  EXPECT_EQ(open_ended.source, "no --duration, no duration_s in the scenario");
  EXPECT_EQ(given.run_length(0.0, true).seconds, 0.0) << "--duration 0: until Ctrl-C whatever the scenario says";
  EXPECT_THROW(given.run_length(0.0, false), SetupError) << "a virtual run must end";
}

TEST(Scenarios, TheLaptopTableNamesTheTeamsSoftwareRelativeToTheFile) {
  const Scenario s = parse_scenario(
      "[laptop]\nrtdb_lib = \"lib/librtdb.so\"\nrtdb_items = \"rtdb_user.h\"\nrtdb_ini = \"/abs/rtdb.ini\"\n"
      "layout = \"cambada\"\npman = \"none\"\ncoach_period_s = 0.5\nreplicate = false\nreplicate_period_s = 0.2\n"
      "relocation_delay_s = 0.25\n",
      "/team/scenarios/s.toml");
  EXPECT_EQ(s.laptop.rtdb_lib, "/team/scenarios/lib/librtdb.so");
  EXPECT_EQ(s.laptop.rtdb_items, "/team/scenarios/rtdb_user.h");
  EXPECT_EQ(s.laptop.rtdb_ini, "/abs/rtdb.ini");
  EXPECT_EQ(s.laptop.layout, "cambada");
  EXPECT_EQ(s.laptop.pman, "none");
  EXPECT_DOUBLE_EQ(s.laptop.coach_period_s, 0.5);
  EXPECT_EQ(s.laptop.replicate, std::optional<bool>(false));
  EXPECT_DOUBLE_EQ(s.laptop.replicate_period_s, 0.2);
  EXPECT_DOUBLE_EQ(s.laptop.relocation_delay_s, 0.25);
  EXPECT_DOUBLE_EQ(parse_scenario("", "s.toml").laptop.relocation_delay_s, kRelocationDelayS);
  EXPECT_NE(error_of("[laptop]\nrelocation_delay_s = -1\n").find("laptop.relocation_delay_s: must be a number"),
            std::string::npos);
  EXPECT_NE(error_of("[laptop]\ncoach_period_s = 0\n").find("bad.toml:2: laptop.coach_period_s: must be a number"),
            std::string::npos)
      << error_of("[laptop]\ncoach_period_s = 0\n");
  EXPECT_NE(error_of("[laptop]\nreplicate = 1\n").find("laptop.replicate: must be true or false"), std::string::npos);
  EXPECT_NE(error_of("[laptop]\npman_lib = \"x\"\n").find("laptop.pman_lib: unknown field"), std::string::npos);
}

TEST(Scenarios, TheExternalTableGivesTheTeamsProcessesAndTheirLimits) {
  const Scenario none = parse_scenario("", "s.toml");
  EXPECT_TRUE(none.external.processes.empty()) << "none: started by hand";
  EXPECT_DOUBLE_EQ(none.external.answer_limit_s, 1.0);
  EXPECT_DOUBLE_EQ(none.external.spin_us, 50);
  EXPECT_DOUBLE_EQ(none.external.bus_spin_us, 200);
  EXPECT_EQ(none.external.syslog, "log") << "syslog messages go to each process's own log";
  const Scenario s = parse_scenario(
      "[external]\nprocesses = [\"./hwcomm --iface {iface}\", \"./agent\"]\nanswer_limit_s = 2.5\n"
      "attach_limit_s = 10\nspin_us = 0\nbus_spin_us = 0\nsyslog = \"system\"\n",
      "s.toml");
  EXPECT_EQ(s.external.syslog, "system");
  EXPECT_NE(error_of("[external]\nsyslog = \"journal\"\n")
                .find("bad.toml:2: external.syslog: must be \"log\" (each process's messages to its own log) or "
                      "\"system\""),
            std::string::npos)
      << error_of("[external]\nsyslog = \"journal\"\n");
  EXPECT_EQ(s.external.processes, (std::vector<std::string>{"./hwcomm --iface {iface}", "./agent"}));
  EXPECT_DOUBLE_EQ(s.external.answer_limit_s, 2.5);
  EXPECT_DOUBLE_EQ(s.external.attach_limit_s, 10);
  EXPECT_DOUBLE_EQ(s.external.spin_us, 0);
  EXPECT_DOUBLE_EQ(s.external.bus_spin_us, 0);
  EXPECT_NE(error_of("[external]\nbus_spin_us = -1\n")
                .find("bad.toml:2: external.bus_spin_us: must be a number from 0 to "
                      "100000"),
            std::string::npos)
      << error_of("[external]\nbus_spin_us = -1\n");
  EXPECT_NE(error_of("[external]\nprocesses = [\"  \"]\n").find("bad.toml:2: external.processes: must be command"),
            std::string::npos)
      << error_of("[external]\nprocesses = [\"  \"]\n");
  EXPECT_NE(error_of("[external]\nanswer_limit_s = 0\n").find("external.answer_limit_s: must be a number from 0.01"),
            std::string::npos);
  EXPECT_NE(error_of("[external]\nprocess = []\n").find("external.process: unknown field"), std::string::npos);
}

TEST(Scenarios, CompleteFillsInTheDefaultsOnce) {
  Scenario s;
  complete(s);
  ASSERT_EQ(s.world.robots.size(), 1u) << "a world without robots gets one";
  EXPECT_DOUBLE_EQ(s.world.robots[0].x_m, kDefaultPlacement.x_m);
  EXPECT_DOUBLE_EQ(s.world.robots[0].heading_deg, kDefaultPlacement.heading_deg);
  EXPECT_EQ(s.interfaces, (std::vector<std::string>{"vcan0"}));
  EXPECT_EQ(s.agents, (std::vector<int>{1}));
  const Scenario again = [&] {
    Scenario t = s;
    complete(t);
    return t;
  }();
  EXPECT_EQ(again.interfaces, s.interfaces) << "idempotent";
  EXPECT_EQ(again.world.robots.size(), 1u);
  const Scenario from_file = parse_scenario("", "empty.toml");
  EXPECT_EQ(from_file.world.robots.size(), 1u) << "a file and code get the same default";
  EXPECT_EQ(from_file.interfaces, s.interfaces);
}

TEST(Scenarios, CompleteRefusesWhatNoRunCanDo) {
  auto error_of = [](Scenario s) {
    try {
      complete(s);
    } catch (const SetupError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  Scenario seven;
  seven.world.robots.assign(7, physics::Placement{});
  EXPECT_NE(error_of(seven).find("at most 6 robots"), std::string::npos) << error_of(seven);
  Scenario two;
  two.world.robots = {physics::Placement{-2, 0, 0}, physics::Placement{2, 0, 0}};
  two.agents = {1};
  EXPECT_NE(error_of(two).find("one interface and one agent number per robot"), std::string::npos);
  two.agents = {1, 7};
  EXPECT_NE(error_of(two).find("agent numbers are 1..6, got 7"), std::string::npos) << error_of(two);
  two.agents = {4, 4};
  EXPECT_NE(error_of(two).find("agent 4 is given to two robots"), std::string::npos) << error_of(two);
  two.agents = {4, 5};
  EXPECT_EQ(error_of(two), "accepted");
}

TEST(Scenarios, TheShippedScenariosLoad) {
  const Scenario five = load_scenario(shipped_scenario("five_robots.toml"));
  EXPECT_EQ(five.world.robots.size(), 5u);
  EXPECT_EQ(five.world.obstacles.size(), 5u);
  EXPECT_EQ(five.interfaces.size(), 5u);
  EXPECT_TRUE(std::filesystem::exists(shipped_scenario("one_robot.toml")));
  const Scenario wire = load_scenario(shipped_scenario("one_robot_on_the_wire.toml"));
  EXPECT_EQ(wire.bus.bit_rate, std::optional<std::uint32_t>(1'000'000)) << "the main job's timed wire";
  ASSERT_EQ(wire.faults.size(), 1u);
  EXPECT_EQ(wire.faults[0].kind, can_nodes::FaultKind::kBusOff);
  EXPECT_TRUE(five.referee.enabled.value_or(false)) << "play goes on after a goal: a kick-off";
  const Scenario strict = parse_scenario("[referee]\nin_play_distance_m = 0.2\n", "strict.toml");
  EXPECT_EQ(strict.referee.in_play_distance_m, 0.2);
}

}  // namespace
}  // namespace canhil::emulator
