// The ziggurat's draws against the normal distribution they stand for:
// moments, the share beyond 1, 2, 3 and 4 sigma, the empirical CDF at every
// 0.25 sigma, and the same draws from the same seed.
#include "canhil/vision_emu/gaussian.hpp"

#include "canhil/vision_emu/noise_engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace canhil::vision_emu {
namespace {

std::vector<float> draws(std::size_t n, unsigned seed, float sigma = 1.0f) {
  NoiseEngine engine(seed);
  const Gaussian g(sigma);
  std::vector<float> out(n);
  for (float& x : out) x = g(engine);
  return out;
}

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

TEST(Gaussian, MomentsAndTailsOfAMillionDraws) {
  const std::vector<float> x = draws(1'000'000, 7);
  double sum = 0;
  double sum2 = 0;
  double sum4 = 0;
  std::array<std::size_t, 4> beyond{};
  for (const float v : x) {
    sum += v;
    sum2 += static_cast<double>(v) * v;
    sum4 += static_cast<double>(v) * v * v * v;
    for (std::size_t k = 0; k < beyond.size(); ++k) {
      if (std::fabs(v) > static_cast<double>(k + 1)) ++beyond[k];
    }
  }
  const auto n = static_cast<double>(x.size());
  EXPECT_NEAR(sum / n, 0.0, 0.005);
  EXPECT_NEAR(sum2 / n, 1.0, 0.005);
  EXPECT_NEAR(sum4 / n, 3.0, 0.05) << "the kurtosis of a normal distribution";
  for (std::size_t k = 0; k < beyond.size(); ++k) {
    const double expected = 2 * (1 - normal_cdf(static_cast<double>(k + 1)));
    const double got = static_cast<double>(beyond[k]) / n;
    // Five standard errors of a share of n draws.
    EXPECT_NEAR(got, expected, 5 * std::sqrt(expected * (1 - expected) / n)) << "beyond " << k + 1 << " sigma";
  }
  EXPECT_GT(*std::max_element(x.begin(), x.end()), 4.0f) << "the tail beyond the base layer is drawn";
  EXPECT_LT(*std::min_element(x.begin(), x.end()), -4.0f);
}

TEST(Gaussian, EmpiricalCdfFollowsTheNormalOne) {
  std::vector<float> x = draws(400'000, 11);
  std::sort(x.begin(), x.end());
  const auto n = static_cast<double>(x.size());
  double worst = 0;
  for (double at = -3.5; at <= 3.5; at += 0.25) {
    const auto below = static_cast<double>(std::lower_bound(x.begin(), x.end(), static_cast<float>(at)) - x.begin());
    worst = std::max(worst, std::fabs(below / n - normal_cdf(at)));
  }
  // Kolmogorov-Smirnov at 0.1 %: 1.95 / sqrt(n).
  EXPECT_LT(worst, 1.95 / std::sqrt(n));
}

TEST(Gaussian, SigmaScalesAndTheSameSeedRepeats) {
  const std::vector<float> a = draws(1000, 3, 0.02f);
  const std::vector<float> b = draws(1000, 3, 0.02f);
  EXPECT_EQ(a, b);
  const std::vector<float> unit = draws(1000, 3);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_FLOAT_EQ(a[i], 0.02f * unit[i]);
  EXPECT_NE(draws(1000, 4, 0.02f), a);
}

}  // namespace
}  // namespace canhil::vision_emu
