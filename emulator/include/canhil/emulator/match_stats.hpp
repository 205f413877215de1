// canhil/emulator/match_stats.hpp — what many matches say (`canhil match
// --report`): wins, draws and losses of the first team, the goal difference
// with a 95 % confidence interval (Student's t), the win rate with a Wilson
// score interval, whether the difference between the teams is significant
// (a two-sided sign test on the decided matches, exact binomial, at 5 %), and
// every other figure per team, per match. Pure functions.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <vector>

namespace canhil::emulator {

/// One match as the statistics see it (a record of `canhil match --records`).
struct MatchSummary {
  std::uint64_t seed = 0;
  bool crashed = false;  ///< no figures: the match did not finish (counted apart)
  std::array<int, 2> goals{};
  std::array<double, 2> possession_s{};
  std::array<int, 2> shots{};
  std::array<int, 2> kicks{};
  std::array<std::uint64_t, 2> faults{};
  std::array<std::uint64_t, 2> ftt_violations{};
  std::uint64_t solver_messages = 0;
  double virtual_s = 0;
  double wall_s = 0;
};

struct Interval {
  double low = 0;
  double high = 0;
};

/// Wilson score interval of a proportion `successes` / `n` (z = 1.96: 95 %).
Interval wilson(int successes, int n, double z = 1.959963984540054);
/// The mean's confidence interval from Student's t with n - 1 degrees of
/// freedom; {mean, mean} for fewer than two values.
Interval mean_interval(const std::vector<double>& values, double level = 0.95);
/// Two-sided exact sign test: the probability, were both teams equal, of a
/// split at least as uneven as `wins` to `losses` (draws left out); 1 when no match was decided.
double sign_test_p(int wins, int losses);

struct TeamFigures {  ///< means per finished match
  double goals = 0;
  double possession_pct = 0;
  double shots = 0;
  double kicks = 0;
  double faults = 0;
  double ftt_violations = 0;
};

struct MatchStats {
  int matches = 0;  ///< finished
  int crashed = 0;
  int wins = 0, draws = 0, losses = 0;  ///< the first team's
  double goal_difference = 0;           ///< mean of first - second
  double goal_difference_sd = 0;
  Interval goal_difference_ci;
  double win_rate = 0;  ///< wins / matches
  Interval win_rate_ci;
  double sign_p = 1;
  bool significant = false;  ///< sign_p < 0.05
  std::array<TeamFigures, 2> teams;
  std::uint64_t solver_messages = 0;
  double virtual_s = 0, wall_s = 0;
  std::map<int, int> goal_difference_histogram;
  /// The win rate and its Wilson interval after each match, in seed order.
  std::vector<double> running_win_rate;
  std::vector<Interval> running_ci;
};

/// Statistics of `matches` (any order: taken in seed order).
MatchStats match_stats(std::vector<MatchSummary> matches);

}  // namespace canhil::emulator
