// canhil/vision_emu/noise_engine.hpp — the random engine behind vision noise
// and detection: PCG32 (O'Neill, 2014), a 64-bit linear congruential state
// whose top bits choose a rotation of a xorshift of it, 32 bits a draw. A
// multiply, an add and a few shifts per draw (std::mt19937 regenerates 624
// words every 624 draws and tempers each), a period of 2^64, and a seeded
// sequence that repeats. A uniform random bit generator: std's distributions
// take it.
#pragma once

#include <bit>
#include <cstdint>

namespace canhil::vision_emu {

class NoiseEngine {
 public:
  using result_type = std::uint32_t;

  /// Nearby seeds (a scenario's seed plus the robot's index) give unrelated
  /// sequences: the seed is scrambled (splitmix64) into the starting state.
  explicit NoiseEngine(std::uint64_t seed = 1) noexcept {
    std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
    state_ = z ^ (z >> 31U);
    (void)(*this)();
  }

  static constexpr result_type min() noexcept { return 0; }
  static constexpr result_type max() noexcept { return 0xFFFFFFFFU; }

  result_type operator()() noexcept {
    const std::uint64_t old = state_;
    state_ = old * kMultiplier + kIncrement;
    const auto mixed = static_cast<std::uint32_t>(((old >> 18U) ^ old) >> 27U);
    return std::rotr(mixed, static_cast<int>(old >> 59U));
  }

  friend bool operator==(const NoiseEngine&, const NoiseEngine&) = default;

 private:
  static constexpr std::uint64_t kMultiplier = 6364136223846793005ULL;
  static constexpr std::uint64_t kIncrement = 1442695040888963407ULL;  // odd: the full period
  std::uint64_t state_ = 0;
};

}  // namespace canhil::vision_emu
