// The shipped test files (emulator/scenarios/tests/) pass with the reference
// handler and agent, and each one's planted regression fails exactly the
// expectations it is about, saying when and what was measured; the same seed
// gives the same verdicts. Each run is a few seconds of virtual time.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "canhil/verdict/verdict.hpp"
#include "support/rtdb_ipc.hpp"
#include "support/test_paths.hpp"

namespace canhil::verdict {
namespace {

namespace fs = std::filesystem;

fs::path example(const std::string& name) { return test::source_dir() + "/emulator/scenarios/tests/" + name; }

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class Examples : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("canhil-verdict-" + std::to_string(getpid()));
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  /// A copy of the example `name` in the test's folder: its scenario the
  /// shipped one, or that with `scenario_edit` applied (one line replaced or
  /// added), and `test_line` added to its [test] table.
  fs::path planted(const std::string& name, const std::string& test_line, const std::string& scenario_from = "",
                   const std::string& scenario_to = "") {
    std::string scenario = read(test::source_dir() + "/emulator/scenarios/one_robot.toml");
    if (!scenario_from.empty()) {
      const auto at = scenario.find(scenario_from);
      if (at == std::string::npos) {
        scenario += scenario_to;
      } else {
        scenario.replace(at, scenario_from.size(), scenario_to);
      }
    }
    std::ofstream(folder_ / "scenario.toml") << scenario;
    std::string text = read(example(name));
    const std::string shipped = "scenario = \"../one_robot.toml\"";
    text.replace(text.find(shipped), shipped.size(), "scenario = \"scenario.toml\"\n" + test_line);
    const fs::path copy = folder_ / name;
    std::ofstream(copy) << text;
    return copy;
  }
  fs::path folder_;
  test::RtdbKeys keys_;  // the runs' RTDB under keys of this test's own
};

std::set<std::string> failed(const FileResult& r) {
  std::set<std::string> names;
  for (const Verdict& v : r.verdicts) {
    if (!v.passed) names.insert(v.name);
  }
  return names;
}

TEST_F(Examples, EveryShippedOnePassesWithTheReferenceHandlerAndAgent) {
  for (const char* name : {"score.toml", "brake_on_silence.toml", "ftt_schedule.toml", "set_pose.toml"}) {
    const FileResult r = run_test_file(example(name), {});
    EXPECT_TRUE(r.error.empty()) << name << ": " << r.error;
    EXPECT_TRUE(r.passed()) << format_result(r);
    EXPECT_GE(r.verdicts.size(), 3U) << name;
  }
}

TEST_F(Examples, AWeakKickFailsOnlyTheGoal) {
  const FileResult r = run_test_file(planted("score.toml", "", "kick_power = 40", "kick_power = 3"), {});
  EXPECT_EQ(failed(r), std::set<std::string>{"scores in the opponent goal by 6 s"}) << format_result(r);
  for (const Verdict& v : r.verdicts) {
    if (v.passed) continue;
    EXPECT_EQ(v.measured, "no goal by 6.00 s");
    EXPECT_NE(v.message.find("no goal in the opponent goal by 6.00 s; the ball ended at"), std::string::npos);
    EXPECT_NE(v.message.find("at t=6.000 s"), std::string::npos) << v.message;
  }
}

TEST_F(Examples, AFirmwareWithoutAQuickWatchdogFailsOnlyTheBrake) {
  const FileResult r =
      run_test_file(planted("brake_on_silence.toml", "", "[firmware]", "\n[firmware]\nwatchdog_ms = 5000\n"), {});
  EXPECT_EQ(failed(r), std::set<std::string>{"stopped within 800 ms of the silence"}) << format_result(r);
  for (const Verdict& v : r.verdicts) {
    if (v.passed) continue;
    EXPECT_NE(v.message.find("never stayed below 0.05 m/s for 200 ms after 'laptop silent' (1.00 s)"),
              std::string::npos)
        << v.message;
    EXPECT_NE(v.message.find("at t=1.800 s"), std::string::npos) << v.message;
  }
}

TEST_F(Examples, TheHandlersM6OneWindowLateFailsOnlyItsWindowAndTheBounds) {
  const FileResult r = run_test_file(planted("ftt_schedule.toml", "faults = [\"delay:M6_1:10\"]"), {});
  EXPECT_EQ(failed(r), (std::set<std::string>{"M6_1 in every window that schedules it",
                                              "schedulable, every observation inside its bound"}))
      << format_result(r);
  for (const Verdict& v : r.verdicts) {
    if (v.name != "M6_1 in every window that schedules it") continue;
    EXPECT_NE(v.message.find("FTT violation(s) of M6_1 on vcan0, at most 0 allowed; the first at "), std::string::npos)
        << v.message;
    EXPECT_NE(v.message.find("M6_1 unscheduled"), std::string::npos) << v.message;
  }
}

TEST_F(Examples, TheHandlersSetPoseFrameLostFailsOnlyTheOdometry) {
  const FileResult r = run_test_file(planted("set_pose.toml", "faults = [\"drop:M5_1\"]"), {});
  EXPECT_EQ(failed(r), (std::set<std::string>{"CMD_POS.x at the set pose", "CMD_POS.y at the set pose"}))
      << format_result(r);
  for (const Verdict& v : r.verdicts) {
    if (v.name != "CMD_POS.x at the set pose") continue;
    EXPECT_NE(v.message.find("CMD_POS.x left [1.49, 1.51], at most 100 ms old from 0.80 s on: "), std::string::npos)
        << v.message;
  }
}

TEST_F(Examples, TheSameSeedGivesTheSameVerdicts) {
  const auto without_wall = [](FileResult r) {
    r.wall_s = 0;
    return to_json_line(r);
  };
  const fs::path f = planted("ftt_schedule.toml", "faults = [\"delay:M6_1:10:0.5\"]");
  EXPECT_EQ(without_wall(run_test_file(f, {})), without_wall(run_test_file(f, {})));
}

TEST_F(Examples, AFileThatCannotRunIsAnErrorNamingWhy) {
  const FileResult missing = run_test_file(folder_ / "none.toml", {});
  EXPECT_FALSE(missing.error.empty());
  EXPECT_FALSE(missing.passed());
  std::ofstream(folder_ / "bad_scenario.toml")
      << "[test]\nscenario = \"nowhere.toml\"\n[[expect]]\nerror_frames_at_most = 0\n";
  const FileResult bad = run_test_file(folder_ / "bad_scenario.toml", {});
  EXPECT_NE(bad.error.find("bad_scenario.toml: [test] scenario "), std::string::npos) << bad.error;
  EXPECT_TRUE(bad.verdicts.empty());
  std::ofstream(folder_ / "robot.toml") << "[test]\nscenario = \"" << test::source_dir()
                                        << "/emulator/scenarios/one_robot.toml\"\n[[expect]]\nrobot = 3\n"
                                           "error_frames_at_most = 0\n";
  EXPECT_NE(
      run_test_file(folder_ / "robot.toml", {}).error.find("robot.toml:3: expect.robot: the scenario has 1 robot(s)"),
      std::string::npos);
  std::ofstream(folder_ / "late.toml") << "[test]\nscenario = \"" << test::source_dir()
                                       << "/emulator/scenarios/one_robot.toml\"\nduration_s = 2\n[[events]]\nat_s = 3\n"
                                          "coach = \"stop\"\n[[expect]]\nerror_frames_at_most = 0\n";
  const std::string late = run_test_file(folder_ / "late.toml", {}).error;
  EXPECT_NE(late.find("late.toml:4: events.at_s: 3 s is not before the run's end (2 s)"), std::string::npos) << late;
}

TEST_F(Examples, ChecksThatCannotBeMetOnWhatTheRunHadFailSayingWhy) {
  // A sporadic message has no period to jitter about; a hold the run ends
  // before is not a hold seen.
  std::ofstream(folder_ / "cannot.toml")
      << "[test]\nscenario = \"" << test::source_dir() << "/emulator/scenarios/one_robot.toml\"\nduration_s = 2\n"
      << "[[events]]\nname = \"stop\"\nat_s = 1.95\ncoach = \"stop\"\n"
      << "[[expect]]\nname = \"M7 jitter\"\njitter_p99_at_most_ms = 0.01\nmessage = \"M7\"\n"
      << "[[expect]]\nname = \"held\"\nspeed_below_m_s = 19\nafter = \"stop\"\nhold_ms = 200\n";
  const FileResult r = run_test_file(folder_ / "cannot.toml", {});
  ASSERT_EQ(r.verdicts.size(), 2U) << r.error;
  EXPECT_FALSE(r.verdicts[0].passed);
  EXPECT_NE(r.verdicts[0].message.find("M7 is sporadic: it has a minimum gap, not a period"), std::string::npos)
      << r.verdicts[0].message;
  EXPECT_FALSE(r.verdicts[1].passed) << "below 19 m/s all along, but the run ends 50 ms after the event: no hold seen";
}

TEST_F(Examples, AnRtdbItemTheLayoutLacksFailsSayingWhatItHas) {
  std::ofstream(folder_ / "item.toml") << "[test]\nscenario = \"" << test::source_dir()
                                       << "/emulator/scenarios/one_robot.toml\"\nduration_s = 0.5\n"
                                          "[[expect]]\nname = \"no such\"\nrtdb = \"CMD_POS.z\"\nbetween = [0, 1]\n";
  const FileResult r = run_test_file(folder_ / "item.toml", {});
  ASSERT_EQ(r.verdicts.size(), 1U) << r.error;
  EXPECT_FALSE(r.verdicts[0].passed);
  EXPECT_NE(r.verdicts[0].message.find("CMD_POS has no quantity z in the layout canhil; it has x, y, heading"),
            std::string::npos)
      << r.verdicts[0].message;
}

}  // namespace
}  // namespace canhil::verdict
