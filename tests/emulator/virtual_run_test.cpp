// The whole loop in virtual time: emulated nodes and physics, the reference
// handler and agent, the emulated vision; deterministic, FTT-clean, and the
// robot scores its purpose: it finds the ball and kicks it towards the goal.
#include "canhil/emulator/virtual_run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

#include "canhil/frames/candump.hpp"
#include "canhil/timing/analysis.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class VirtualRunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    setenv("RTDB_KEY", std::to_string(0x59000000 + ((getpid() & 0xFFF) << 12) + (++counter << 6)).c_str(), 1);
  }
  static VirtualRunConfig one_robot() {
    VirtualRunConfig c;
    c.messages = frames::MessageSet::load(test::shipped_dbc());
    c.world.robots = {physics::Placement{-3.0, 0.0, -90}};  // facing the opponent goal (+x)
    c.world.ball_start = {-1.0, 1.0, c.world.ball.radius_m};
    return c;
  }
};

TEST_F(VirtualRunTest, SameScenarioSameTraceByteForByte) {
  std::string first;
  {
    VirtualRun run(one_robot());
    run.run_for(3s);
    first = run.trace();
  }
  VirtualRun again(one_robot());
  again.run_for(3s);
  EXPECT_EQ(again.trace(), first);
  EXPECT_GT(first.size(), 50'000u);
}

TEST_F(VirtualRunTest, TheTraceIsFttCompliant) {
  VirtualRun run(one_robot());
  run.run_for(4s);
  const VirtualRunConfig cfg = one_robot();
  timing::TimingAnalyzer analyzer(cfg.messages, timing::TimingConfig{});
  std::istringstream in(run.trace());
  std::string line;
  while (std::getline(in, line)) {
    frames::LogEntry e;
    ASSERT_TRUE(frames::parse_log_line(line, e));
    analyzer.add({e.frame, e.time});
  }
  const timing::TimingReport report = analyzer.finish();
  EXPECT_TRUE(report.ok()) << timing::format_table(report);
  EXPECT_EQ(report.unknown, 0u);
  EXPECT_EQ(run.outcomes()[0].bad_frames, 0u);
}

TEST_F(VirtualRunTest, TheRobotFindsTheBallAndKicksItTowardsTheGoal) {
  VirtualRun run(one_robot());
  const double start_x = run.world().ball_position().x();
  bool kicked = false;
  for (int second = 0; second < 30 && !kicked; ++second) {
    run.run_for(1s);
    kicked = run.outcomes()[0].kicks > 0;
  }
  ASSERT_TRUE(kicked) << "the agent never kicked; robot at (" << run.outcomes()[0].pose.x_m << ", "
                      << run.outcomes()[0].pose.y_m << "), ball at (" << run.world().ball_position().x() << ", "
                      << run.world().ball_position().y() << ")";
  run.run_for(2s);
  const Eigen::Vector3d ball = run.world().ball_position();
  EXPECT_GT(ball.x(), start_x + 3.0) << "the ball went towards the opponent goal (+x)";
  EXPECT_LT(std::fabs(ball.y()), 3.0);
}

}  // namespace
}  // namespace canhil::emulator
