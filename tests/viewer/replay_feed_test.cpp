// A recorded run for the viewer: the world log's rows, goals and kicks found,
// the trace's frames around a time, and malformed files named with their line.
#include "canhil/viewer/replay_feed.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <vector>

#include "support/test_paths.hpp"

namespace canhil::viewer {
namespace {

class ReplayFeedTest : public ::testing::Test {
 protected:
  ReplayFeedTest() { std::filesystem::create_directories(dir_); }
  ~ReplayFeedTest() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  ReplayFeed feed(const std::filesystem::path& log, std::optional<std::filesystem::path> trace = std::nullopt) {
    return ReplayFeed(log, trace, physics::WorldParams{}, frames::MessageSet::load(test::shipped_dbc()));
  }
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() / ("canhil-replay-" + std::to_string(getpid()));
};

const char* kHeader =
    "time_s,ball_x_m,ball_y_m,ball_z_m,robot0_x_m,robot0_y_m,robot0_heading_deg,robot0_reported_x_m,"
    "robot0_reported_y_m,robot0_reported_heading_deg\n";

TEST_F(ReplayFeedTest, TheRefereesCallsAreMarksOtherCommentsAreSkipped) {
  std::string log = kHeader;
  log += "0.0,5,0,0.11,-3,0,-90,-3,0,-90\n";
  log += "# a comment line\n";
  log += "0.1,5,0,0.11,-3,0,-90,-3,0,-90\n";
  log += "#referee,0.150,throwin,old,2.500,-6.000,1,0\n";
  log += "#referee,0.180,drop_ball,-,0.000,0.000,1,0\n";
  log += "#referee,not-a-time,throwin,old,0,0\n";  // not a call: skipped like any comment
  log += "0.2,5,0,0.11,-3,0,-90,-3,0,-90\n";
  const auto f = feed(write("r.csv", log));
  EXPECT_EQ(f.rows(), 3u);
  ASSERT_EQ(f.events().size(), 2u);
  EXPECT_EQ(f.events()[0].kind, "referee");
  EXPECT_NEAR(f.events()[0].time_s, 0.15, 1e-9);
  EXPECT_EQ(f.events()[0].text, "throwin for old, score 1:0");
  EXPECT_EQ(f.events()[1].text, "drop_ball, score 1:0");
}

TEST_F(ReplayFeedTest, TeamsAndRobotsFromTheirLinesAreInTheHello) {
  const std::string two_robots =
      "time_s,ball_x_m,ball_y_m,ball_z_m,robot0_x_m,robot0_y_m,robot0_heading_deg,robot0_reported_x_m,"
      "robot0_reported_y_m,robot0_reported_heading_deg,robot1_x_m,robot1_y_m,robot1_heading_deg,robot1_reported_x_m,"
      "robot1_reported_y_m,robot1_reported_heading_deg\n";
  const std::string row = ",0,0,0.11,-3,0,-90,-3,0,-90,3,0,90,3,0,90\n";
  std::string log = two_robots;
  log += "#team,0,new,+x\n#team,1,old,-x\n#robot,0,0,3,vcan0\n#robot,1,1,3,vcan5\n";
  log += "#team,2,third,sideways\n#robot,7,0,1,vcan7\n#robot,1,x,1,vcan1\n";  // not so: comments
  log += "0.0" + row + "0.1" + row;
  auto f = feed(write("teams.csv", log));
  ASSERT_EQ(f.teams().size(), 2u);
  EXPECT_EQ(f.teams()[1].name, "old");
  EXPECT_FALSE(f.teams()[1].attacks_positive_x);
  const nlohmann::json h = f.hello();
  ASSERT_EQ(h["teams"].size(), 2u);
  EXPECT_EQ(h["teams"][0]["name"], "new");
  EXPECT_EQ(h["teams"][0]["attacks_positive_x"], true);
  ASSERT_EQ(h["robots"].size(), 2u);
  EXPECT_EQ(h["robots"][1]["team"], 1);
  EXPECT_EQ(h["robots"][1]["agent"], 3) << "both teams use agent numbers from 1";
  EXPECT_EQ(h["robots"][1]["interface"], "vcan5");
  EXPECT_EQ(f.rows(), 2u);
  // Without the lines (one team, or an older log): one team, robots numbered in order.
  auto plain = feed(write("plain.csv", two_robots + "0.0" + row));
  const nlohmann::json p = plain.hello();
  EXPECT_TRUE(p["teams"].empty());
  EXPECT_EQ(p["robots"][1]["team"], 0);
  EXPECT_EQ(p["robots"][1]["agent"], 2);
  EXPECT_EQ(p["robots"][1]["interface"], "robot 1");
}

TEST_F(ReplayFeedTest, RowsGoalsAndKicksFromTheBallAlone) {
  std::string log = kHeader;
  // The ball lies still, is kicked at 0.2 s and rolls into the +x goal (x > 9.11).
  const double xs[] = {5.0, 5.0, 5.0, 6.0, 7.0, 8.0, 9.0, 9.5, 9.6, 9.6};
  for (int i = 0; i < 10; ++i) {
    log += std::to_string(i * 0.1) + "," + std::to_string(xs[i]) + ",0,0.11,-3,0,-90,-3,0,-90\n";
  }
  const auto f = feed(write("w.csv", log));
  EXPECT_EQ(f.robots(), 1u);
  EXPECT_EQ(f.rows(), 10u);
  ASSERT_EQ(f.events().size(), 2u);
  EXPECT_EQ(f.events()[0].kind, "kick");
  EXPECT_NEAR(f.events()[0].time_s, 0.3, 1e-9);
  EXPECT_EQ(f.events()[1].kind, "goal");
  EXPECT_NEAR(f.events()[1].time_s, 0.7, 1e-9);
  EXPECT_EQ(f.events()[1].positive_x, true);
  EXPECT_FALSE(f.events()[0].positive_x);  // a kick has no side
  ReplayFeed copy = feed(write("w.csv", log));
  const auto body = nlohmann::json::parse(*copy.api("replay", ""));
  EXPECT_EQ(body["rows"].size(), 10u);
  EXPECT_EQ(body["events"][1]["positive_x"], true);
  EXPECT_FALSE(body["events"][0].contains("positive_x"));
  EXPECT_EQ(body["rows"][3][1], 6.0);
  EXPECT_EQ(copy.hello()["mode"], "replay");
  EXPECT_FALSE(copy.api("nothing", ""));
  EXPECT_EQ(copy.request("{}")["ok"], false);
}

TEST_F(ReplayFeedTest, AGoalInTheMinusXGoalSaysSoAndTheHelloGivesTheLength) {
  std::string log = kHeader;
  const double xs[] = {-8.0, -9.0, -9.6, -9.6, -8.0, -9.6};  // in, out again, in again: two goals
  for (int i = 0; i < 6; ++i) {
    log += std::to_string(i * 0.1) + "," + std::to_string(xs[i]) + ",0.2,0.11,-3,0,-90,-3,0,-90\n";
  }
  auto f = feed(write("w.csv", log));
  std::vector<double> goals;
  for (const auto& e : f.events()) {
    if (e.kind != "goal") continue;
    goals.push_back(e.time_s);
    EXPECT_EQ(e.positive_x, false) << e.text;
  }
  ASSERT_EQ(goals.size(), 2u);
  EXPECT_NEAR(goals[0], 0.2, 1e-9);
  EXPECT_NEAR(goals[1], 0.5, 1e-9);
  const auto hello = f.hello();
  EXPECT_NEAR(hello["duration_s"].get<double>(), 0.5, 1e-9);
  EXPECT_EQ(hello["rows"], 6u);
  EXPECT_EQ(hello["has_trace"], false);
}

TEST_F(ReplayFeedTest, KicksFromTheTraceAndFramesAroundATimeDecoded) {
  std::string log = kHeader;
  log += "0,0,0,0.11,-3,0,-90,-3,0,-90\n1,0,0,0.11,-3,0,-90,-3,0,-90\n";
  // M7 (0x0B0): kick byte 0x8A = a low kick of power 10; 131 is M6_1.
  const std::string trace =
      "(0.100000) vcan0 131#F401000000000000\n"
      "(0.500000) vcan0 0B0#8A00000000000000\n"
      "(0.600000) vcan0 0B0#0000000000000000\n";
  auto f = feed(write("w.csv", log), write("t.log", trace));
  EXPECT_EQ(f.hello()["has_trace"], true);
  ASSERT_EQ(f.events().size(), 1u);
  EXPECT_EQ(f.events()[0].kind, "kick");
  EXPECT_NEAR(f.events()[0].time_s, 0.5, 1e-9);
  EXPECT_NE(f.events()[0].text.find("power 10"), std::string::npos) << f.events()[0].text;
  const auto frames = f.frames_between(0.05, 0.55);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0]["name"], "M6_1");
  EXPECT_NE(frames[0]["signals"].get<std::string>().find("vx=0.500"), std::string::npos) << frames[0];
  EXPECT_EQ(nlohmann::json::parse(*f.api("frames", "from=0.45&to=0.7")).size(), 2u);
  EXPECT_EQ(f.frames_between(0, 10, 1).size(), 1u);  // at most as many as asked
}

TEST_F(ReplayFeedTest, MalformedFilesAreNamedWithTheirLine) {
  const auto message = [&](const std::string& log, const std::string& trace = "") {
    try {
      if (trace.empty()) {
        feed(write("bad.csv", log));
      } else {
        feed(write("bad.csv", log), write("bad.log", trace));
      }
    } catch (const SetupError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("a,b,c\n1,2,3\n").find("bad.csv:1: not a world log"), std::string::npos);
  EXPECT_NE(message(std::string(kHeader) + "0,0,0,0.11,-3,0,-90,-3,0\n").find("bad.csv:2: 9 values"),
            std::string::npos);
  EXPECT_NE(message(std::string(kHeader) + "0,0,x,0.11,-3,0,-90,-3,0,-90\n").find("bad.csv:2: 'x'"), std::string::npos);
  EXPECT_NE(message(std::string(kHeader) + "1,0,0,0.11,-3,0,-90,-3,0,-90\n0,0,0,0.11,-3,0,-90,-3,0,-90\n")
                .find("bad.csv:3: time goes back"),
            std::string::npos);
  EXPECT_NE(message(kHeader).find("no rows"), std::string::npos);
  EXPECT_NE(message(std::string(kHeader) + "0,0,0,0.11,-3,0,-90,-3,0,-90\n", "(0.1) vcan0 zz\n").find("bad.log:1:"),
            std::string::npos);
}

}  // namespace
}  // namespace canhil::viewer
