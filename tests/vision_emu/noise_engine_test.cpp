// The vision's random engine: uniform bits (every byte value as often as
// chance allows, every bit set half the time), repeatable from a seed,
// unrelated sequences from neighbouring seeds, and usable by std's
// distributions.
#include "canhil/vision_emu/noise_engine.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <random>

namespace canhil::vision_emu {
namespace {

TEST(NoiseEngine, BytesAndBitsAreUniform) {
  NoiseEngine e(12345);
  constexpr int kDraws = 1 << 20;
  std::array<std::array<double, 256>, 4> bytes{};
  std::array<double, 32> ones{};
  for (int i = 0; i < kDraws; ++i) {
    const std::uint32_t x = e();
    for (std::size_t b = 0; b < 4; ++b) bytes[b][(x >> (8 * b)) & 0xFFU] += 1;
    for (std::size_t bit = 0; bit < 32; ++bit) ones[bit] += (x >> bit) & 1U;
  }
  const double expected = kDraws / 256.0;
  for (std::size_t b = 0; b < 4; ++b) {
    double chi2 = 0;
    for (const double n : bytes[b]) chi2 += (n - expected) * (n - expected) / expected;
    // 255 degrees of freedom: beyond 340 has a chance of about 1 in 4000.
    EXPECT_LT(chi2, 340) << "byte " << b;
    EXPECT_GT(chi2, 180) << "byte " << b << ": too even to be random";
  }
  for (std::size_t bit = 0; bit < 32; ++bit) {
    EXPECT_NEAR(ones[bit] / kDraws, 0.5, 5 * 0.5 / std::sqrt(kDraws)) << "bit " << bit;
  }
}

TEST(NoiseEngine, ASeedRepeatsAndNeighbouringSeedsAreUnrelated) {
  NoiseEngine a(7);
  NoiseEngine b(7);
  NoiseEngine c(8);
  int same_bits = 0;
  for (int i = 0; i < 1000; ++i) {
    const std::uint32_t x = a();
    EXPECT_EQ(x, b());
    same_bits += 32 - std::popcount(x ^ c());
  }
  EXPECT_NEAR(same_bits / 32000.0, 0.5, 0.02) << "seeds 7 and 8 agree on a bit half the time, as strangers do";
  EXPECT_EQ(a, b);
}

TEST(NoiseEngine, DrivesStdDistributions) {
  NoiseEngine e(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  double sum = 0;
  for (int i = 0; i < 100000; ++i) {
    const float x = u(e);
    ASSERT_GE(x, 0.0f);
    ASSERT_LT(x, 1.0f);
    sum += x;
  }
  EXPECT_NEAR(sum / 100000, 0.5, 0.005);
}

}  // namespace
}  // namespace canhil::vision_emu
