#include "canhil/emulator/match_stats.hpp"

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>

namespace canhil::emulator {

Interval wilson(int successes, int n, double z) {
  if (n <= 0) return {0, 1};
  const double p = static_cast<double>(successes) / n;
  const double z2 = z * z;
  const double scale = 1 + z2 / n;
  const double centre = (p + z2 / (2.0 * n)) / scale;
  const double half = z * std::sqrt(p * (1 - p) / n + z2 / (4.0 * n * n)) / scale;
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

Interval mean_interval(const std::vector<double>& values, double level) {
  const auto n = static_cast<double>(values.size());
  double mean = 0;
  for (const double v : values) mean += v;
  mean = values.empty() ? 0 : mean / n;
  if (values.size() < 2) return {mean, mean};
  double ss = 0;
  for (const double v : values) ss += (v - mean) * (v - mean);
  const double sd = std::sqrt(ss / (n - 1));
  const boost::math::students_t t(n - 1);
  const double half = boost::math::quantile(boost::math::complement(t, (1 - level) / 2)) * sd / std::sqrt(n);
  return {mean - half, mean + half};
}

double sign_test_p(int wins, int losses) {
  const int n = wins + losses;
  if (n == 0) return 1;
  const boost::math::binomial b(n, 0.5);
  const int k = std::min(wins, losses);
  return std::min(1.0, 2 * boost::math::cdf(b, k));
}

MatchStats match_stats(std::vector<MatchSummary> matches) {
  std::sort(matches.begin(), matches.end(),
            [](const MatchSummary& a, const MatchSummary& b) { return a.seed < b.seed; });
  MatchStats s;
  std::vector<double> differences;
  for (const MatchSummary& m : matches) {
    if (m.crashed) {
      ++s.crashed;
      continue;
    }
    ++s.matches;
    const int d = m.goals[0] - m.goals[1];
    differences.push_back(d);
    ++s.goal_difference_histogram[d];
    (d > 0 ? s.wins : d < 0 ? s.losses : s.draws)++;
    const double possession = m.possession_s[0] + m.possession_s[1];
    for (std::size_t t = 0; t < 2; ++t) {
      TeamFigures& f = s.teams[t];
      f.goals += m.goals[t];
      f.possession_pct += possession > 0 ? 100 * m.possession_s[t] / possession : 0;
      f.shots += m.shots[t];
      f.kicks += m.kicks[t];
      f.faults += static_cast<double>(m.faults[t]);
      f.ftt_violations += static_cast<double>(m.ftt_violations[t]);
    }
    s.solver_messages += m.solver_messages;
    s.virtual_s += m.virtual_s;
    s.wall_s += m.wall_s;
    s.running_win_rate.push_back(static_cast<double>(s.wins) / s.matches);
    s.running_ci.push_back(wilson(s.wins, s.matches));
  }
  if (s.matches == 0) return s;
  const double n = s.matches;
  for (TeamFigures& f : s.teams) {
    f.goals /= n;
    f.possession_pct /= n;
    f.shots /= n;
    f.kicks /= n;
    f.faults /= n;
    f.ftt_violations /= n;
  }
  s.goal_difference_ci = mean_interval(differences);
  s.goal_difference = (s.goal_difference_ci.low + s.goal_difference_ci.high) / 2;
  double ss = 0;
  for (const double d : differences) ss += (d - s.goal_difference) * (d - s.goal_difference);
  s.goal_difference_sd = differences.size() > 1 ? std::sqrt(ss / (n - 1)) : 0;
  s.win_rate = s.wins / n;
  s.win_rate_ci = wilson(s.wins, s.matches);
  s.sign_p = sign_test_p(s.wins, s.losses);
  s.significant = s.sign_p < 0.05;
  return s;
}

}  // namespace canhil::emulator
