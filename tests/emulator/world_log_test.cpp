// The world log read back as written: its header, who played for whom, rows
// and the referee's calls; a log written by hand is read with its mistakes
// named by file and line, and an unknown '#' line is a comment.
#include "canhil/emulator/world_log.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

#include "support/counter_watch.hpp"
#include "support/error_of.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class WorldLogTest : public test::WatchedTest {
 protected:
  std::filesystem::path write(const std::string& text) {
    std::ofstream(path_) << text;
    return path_;
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::filesystem::path path_ =
      std::filesystem::temp_directory_path() / ("canhil-world-log-" + std::to_string(getpid()) + ".csv");
};

TEST_F(WorldLogTest, WhatIsWrittenReadsBack) {
  WorldLogWriter w(Nanos{50ms}, {{"home", true}, {"away", false}}, {{0, 1, "vcan0"}, {1, 2, "vcan1"}});
  for (const Nanos t : {Nanos{0}, Nanos{20ms}, Nanos{50ms}}) {
    if (!w.due(t)) continue;
    w.begin_row(t, {1.0, -2.0, 0.11});
    w.robot({-1, 0, 0}, {-0.99, 0.01, 0});
    w.robot({1, 0.5, M_PI}, {});
    w.end_row();
  }
  w.call({0.06, "throwin", "away", 3.0, 6.0, {"0", "1"}});
  const WorldLog log = read_world_log(write(w.text()));
  EXPECT_EQ(log.robots, 2u);
  EXPECT_EQ(log.columns.size(), 4u + 12u);
  EXPECT_EQ(log.columns[9], "robot0_reported_heading_deg");
  ASSERT_EQ(log.rows.size(), 2u) << "one row every 50 ms from 0: the one at 20 ms is not due";
  EXPECT_DOUBLE_EQ(log.rows[1][0], 0.05);
  EXPECT_DOUBLE_EQ(log.rows[1][7], -0.99);
  EXPECT_DOUBLE_EQ(log.rows[1][12], 180.0);
  ASSERT_EQ(log.teams.size(), 2u);
  EXPECT_EQ(log.teams[1].name, "away");
  EXPECT_FALSE(log.teams[1].attacks_positive_x);
  ASSERT_EQ(log.robot_info.size(), 2u);
  EXPECT_EQ(log.robot_info[1].team, 1u);
  EXPECT_EQ(log.robot_info[1].agent, 2);
  EXPECT_EQ(log.robot_info[1].interface, "vcan1");
  ASSERT_EQ(log.calls.size(), 1u);
  EXPECT_EQ(log.calls[0].restart, "throwin");
  EXPECT_EQ(log.calls[0].team, "away");
  EXPECT_DOUBLE_EQ(log.calls[0].spot_y_m, 6.0);
  EXPECT_EQ(log.calls[0].score, (std::vector<std::string>{"0", "1"}));
}

TEST_F(WorldLogTest, OneTeamsLogSaysNoTeamAndItsRobotsAreNumbered) {
  WorldLogWriter w(Nanos{50ms}, {{"only", true}}, {{0, 1, "vcan0"}});
  w.begin_row(Nanos{0}, {0, 0, 0.11});
  w.robot({}, {});
  w.end_row();
  EXPECT_EQ(w.text().find('#'), std::string::npos) << w.text();
  std::string text = w.text();
  text.insert(text.find('\n') + 1, "#a comment\n");
  const WorldLog log = read_world_log(write(text + "#team,7,x,+x\n"));
  EXPECT_TRUE(log.teams.empty());
  EXPECT_EQ(log.robot_info[0].agent, 1);
  EXPECT_EQ(log.robot_info[0].interface, "robot 0");
}

TEST_F(WorldLogTest, MistakesAreNamedByFileAndLine) {
  const std::string header = "time_s,ball_x_m,ball_y_m,ball_z_m\n";
  EXPECT_NE(test::error_of([&] { read_world_log(write("a,b\n0,1\n")); }).find(":1: not a world log"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { read_world_log(write(header + "0,0,0,0\n1,0,0\n")); }).find(":3: 3 values"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { read_world_log(write(header + "0,0,x,0\n")); }).find(":2: 'x' is not a number"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { read_world_log(write(header + "1,0,0,0\n0,0,0,0\n")); }).find(":3: time goes back"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { read_world_log(write(header)); }).find("no rows"), std::string::npos);
}

}  // namespace
}  // namespace canhil::emulator
