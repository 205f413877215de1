// A test file read and checked (verdict/test_file.hpp): what it holds, and
// every mistake named with the file, the line and the field.
#include "canhil/verdict/test_file.hpp"

#include <gtest/gtest.h>

#include <string>

#include "canhil/physics/config.hpp"
#include "support/error_of.hpp"

namespace canhil::verdict {
namespace {

const std::string kHead = "[test]\nscenario = \"../one_robot.toml\"\n";
const std::string kExpect = "[[expect]]\nerror_frames_at_most = 0\n";

std::string error_of(const std::string& text) {
  return test::error_of<physics::ConfigError>([&] { parse_test_file(text, "dir/t.toml"); });
}

TEST(TestFile, HoldsTheScenarioEventsInTimeOrderAndExpectations) {
  const TestFile f = parse_test_file(kHead +
                                         "duration_s = 3\nseed = 7\nfaults = [\"drop:M4_1:0.1\"]\n"
                                         "[[events]]\nname = \"late\"\nat_s = 2\ncoach = \"stop\"\n"
                                         "[[events]]\nat_s = 1\nfault = \"silence:laptop:0\"\n"
                                         "[[events]]\nat_s = 1.5\nset_pose = [1, 2, 0.5]\n"
                                         "[[expect]]\nname = \"brakes\"\nspeed_below_m_s = 0.1\nafter = \"late\"\n"
                                         "[[expect]]\nrtdb = \"CMD_POS.x\"\nbetween = [1, 2]\nat_s = 1\n",
                                     "dir/t.toml");
  EXPECT_EQ(f.name, "t") << "the file's name when [test] names none";
  EXPECT_EQ(f.scenario, std::filesystem::path("dir/../one_robot.toml")) << "relative to the test file";
  EXPECT_EQ(f.duration_s, 3.0);
  EXPECT_EQ(f.seed, 7U);
  ASSERT_EQ(f.events.size(), 3U);
  EXPECT_EQ(f.events[0].name, "event 2") << "sorted by time, named by their place in the file";
  EXPECT_EQ(f.events[0].kind, Event::Kind::kFault);
  EXPECT_EQ(f.events[1].kind, Event::Kind::kSetPose);
  EXPECT_DOUBLE_EQ(f.events[1].pose.y_m, 2.0);
  EXPECT_EQ(f.events[2].game_state, "stop");
  ASSERT_EQ(f.expectations.size(), 2U);
  EXPECT_EQ(f.expectations[0].check, Check::kSpeedBelow);
  EXPECT_DOUBLE_EQ(f.expectations[0].within_ms, 500) << "the default";
  EXPECT_EQ(f.expectations[1].item, "CMD_POS");
  EXPECT_EQ(f.expectations[1].quantity, "x");
  EXPECT_EQ(f.expectations[1].name, "rtdb (expectation 2)");
}

TEST(TestFile, MistakesNameTheFileTheLineTheFieldAndWhatToWrite) {
  EXPECT_NE(error_of(kExpect).find("dir/t.toml:1: test: missing: a test file starts with [test]"), std::string::npos);
  EXPECT_NE(error_of("[test]\n" + kExpect).find("test.scenario: missing"), std::string::npos);
  EXPECT_NE(error_of(kHead).find("expect: missing: a test expects something"), std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nname = \"x\"\n")
                .find("dir/t.toml:3: expect: says nothing to check; give one of "
                      "ball_in_goal, robot_near"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nball_in_goal = \"opponent\"\nerror_frames_at_most = 0\n")
                .find("dir/t.toml:5: expect.error_frames_at_most: an expectation checks one thing"),
            std::string::npos)
      << error_of(kHead + "[[expect]]\nball_in_goal = \"opponent\"\nerror_frames_at_most = 0\n");
  EXPECT_NE(
      error_of(kHead + "[[expect]]\nball_in_goal = \"theirs\"\n").find("dir/t.toml:4: expect.ball_in_goal: must be"),
      std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nerror_frames_at_most = 0\nwithin_m = 2\n")
                .find("dir/t.toml:5: expect.within_m: unknown field; known here: name, robot, error_frames_at_most"),
            std::string::npos)
      << "a field another check takes";
  EXPECT_NE(error_of(kHead + "[[expect]]\nspeed_below_m_s = 0.1\nafter = \"silence\"\n")
                .find("expect.after: no event is named 'silence'; the events are none"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nspeed_below_m_s = 0.1\n").find("give after = \"EVENT\""), std::string::npos);
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nat_s = 1\nfault = \"drop:M1:7\"\n")
                .find("dir/t.toml:7: events.fault: fault 'drop:M1:7': the probability"),
            std::string::npos)
      << error_of(kHead + kExpect + "[[events]]\nat_s = 1\nfault = \"drop:M1:7\"\n");
  EXPECT_NE(
      error_of(kHead + kExpect + "[[events]]\nat_s = 1\ncoach = \"pause\"\n").find("events.coach: not a game state"),
      std::string::npos);
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nat_s = 1\n").find("give exactly one of fault"), std::string::npos);
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nfault = \"drop:M1\"\n").find("events.at_s: missing"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nat_s = 1\nball = [1]\n").find("events.ball: give [x_m, y_m]"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nrtdb = \"CMD_POS\"\nbetween = [0, 1]\n").find("must be ITEM.quantity"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nrtdb = \"CMD_POS.x\"\nbetween = [2, 1]\n").find("the low bound comes first"),
            std::string::npos);
  EXPECT_EQ(error_of(kHead + kExpect + kExpect), "(no error)") << "two unnamed ones are told apart by their place";
  const std::string named = "[[expect]]\nname = \"quiet\"\nerror_frames_at_most = 0\n";
  EXPECT_NE(error_of(kHead + named + named).find("dir/t.toml:6: expect.name: 'quiet' names two expectations"),
            std::string::npos);
  EXPECT_NE(
      error_of("[run]\nseed = 1\n[[robots]]\nx_m = 0\n").find("dir/t.toml:1: run: this is a scenario, not a test file"),
      std::string::npos)
      << error_of("[run]\nseed = 1\n[[robots]]\nx_m = 0\n");
  EXPECT_NE(error_of(kHead + kExpect + "[tset]\n").find("dir/t.toml:5: tset: unknown table"), std::string::npos);
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nat_s = 1\ncoach = \"stop\"\nrobot = 1\n")
                .find("dir/t.toml:8: events.robot: a coach order for one robot says whether it plays"),
            std::string::npos)
      << "robot without running: not silently every team's";
  EXPECT_NE(error_of(kHead + kExpect + "[[events]]\nat_s = 1\nball = [0, 0]\nrunning = true\n")
                .find("events.running: only a coach order"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "bit_rate = 5000\n" + kExpect)
                .find("dir/t.toml:3: test.bit_rate: must be 0 (the instant bus) or"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "seed = 1.5\n" + kExpect).find("test.seed: must be a whole number"), std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nrtdb = \"CMD_POS.x\"\nbetween = [0, 1]\nat_s = 1\nfrom_s = 2\n")
                .find("expect.from_s: give at_s (at one instant) or from_s"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "[[expect]]\nrobot_near = \"ball\"\nfrom_s = 3\nby_s = 2\n")
                .find("expect.by_s: comes before from_s"),
            std::string::npos);
  EXPECT_NE(error_of(kHead + "seed = -1\n" + kExpect).find("test.seed: must be a number from 0"), std::string::npos);
}

}  // namespace
}  // namespace canhil::verdict
