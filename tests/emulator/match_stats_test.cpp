// The statistics of many matches on figures worked out by hand.
#include "canhil/emulator/match_stats.hpp"

#include <gtest/gtest.h>

namespace canhil::emulator {
namespace {

TEST(MatchStats, WilsonIntervalOfSixWinsInTen) {
  // p = 0.6, z = 1.96, n = 10: centre (0.6 + 1.96^2/20) / (1 + 1.96^2/10) =
  // 0.79208 / 1.38415 = 0.57225; half 1.96 sqrt(0.024 + 0.009604) / 1.38415 = 0.25958.
  const Interval i = wilson(6, 10);
  EXPECT_NEAR(i.low, 0.31267, 1e-5);
  EXPECT_NEAR(i.high, 0.83182, 1e-5);
  // None in five: the interval still reaches 0.434, not 0..0 as p +- z sqrt(p(1-p)/n) would say.
  EXPECT_DOUBLE_EQ(wilson(0, 5).low, 0.0);
  EXPECT_NEAR(wilson(0, 5).high, 0.43448, 1e-5);
}

TEST(MatchStats, StudentIntervalOfTheMean) {
  // 1..5: mean 3, sd sqrt(2.5) = 1.58114, t(0.975, 4) = 2.77645: 3 +- 1.96324.
  const Interval i = mean_interval({1, 2, 3, 4, 5});
  EXPECT_NEAR(i.low, 1.03676, 1e-5);
  EXPECT_NEAR(i.high, 4.96324, 1e-5);
  EXPECT_DOUBLE_EQ(mean_interval({2}).low, 2.0) << "one value: no spread to know";
}

TEST(MatchStats, SignTestOnTheDecidedMatches) {
  // 6 to 2: P(X <= 2) = (1 + 8 + 28) / 256, twice: 0.2890625.
  EXPECT_DOUBLE_EQ(sign_test_p(6, 2), 74.0 / 256);
  // 9 to 1: (1 + 10) / 1024, twice: 0.021484375.
  EXPECT_DOUBLE_EQ(sign_test_p(9, 1), 22.0 / 1024);
  EXPECT_DOUBLE_EQ(sign_test_p(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(sign_test_p(3, 3), 1.0);
}

MatchSummary match(std::uint64_t seed, int a, int b) {
  MatchSummary m;
  m.seed = seed;
  m.goals = {a, b};
  m.possession_s = {30, 10};
  m.shots = {a + 1, b};
  return m;
}

TEST(MatchStats, AllTogetherInSeedOrderWhateverTheOrderGiven) {
  MatchSummary crashed;
  crashed.seed = 4;
  crashed.crashed = true;
  const MatchStats s = match_stats({match(3, 0, 1), crashed, match(1, 2, 0), match(2, 1, 1)});
  EXPECT_EQ(s.matches, 3);
  EXPECT_EQ(s.crashed, 1);
  EXPECT_EQ(s.wins, 1);
  EXPECT_EQ(s.draws, 1);
  EXPECT_EQ(s.losses, 1);
  EXPECT_DOUBLE_EQ(s.goal_difference, (2 + 0 - 1) / 3.0);
  EXPECT_DOUBLE_EQ(s.win_rate, 1 / 3.0);
  EXPECT_DOUBLE_EQ(s.sign_p, 1.0);
  EXPECT_FALSE(s.significant);
  EXPECT_DOUBLE_EQ(s.teams[0].possession_pct, 75.0);
  EXPECT_DOUBLE_EQ(s.teams[0].shots, (3 + 2 + 1) / 3.0);
  EXPECT_EQ(s.goal_difference_histogram, (std::map<int, int>{{-1, 1}, {0, 1}, {2, 1}}));
  // Seed 1 (a win), then 2 (a draw), then 3 (a loss).
  EXPECT_EQ(s.running_win_rate, (std::vector<double>{1.0, 0.5, 1 / 3.0}));
}

TEST(MatchStats, NineWinsInTenIsSignificant) {
  std::vector<MatchSummary> ms;
  for (std::uint64_t k = 0; k < 10; ++k) ms.push_back(match(k, k == 0 ? 0 : 2, k == 0 ? 1 : 0));
  const MatchStats s = match_stats(ms);
  EXPECT_EQ(s.wins, 9);
  EXPECT_DOUBLE_EQ(s.sign_p, 22.0 / 1024);
  EXPECT_TRUE(s.significant);
  EXPECT_GT(s.goal_difference_ci.low, 0) << "the goal difference's interval is above 0 too";
}

}  // namespace
}  // namespace canhil::emulator
