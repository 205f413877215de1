// canhil/vision_emu/gaussian.hpp — normal draws for vision noise, by the
// ziggurat method (Marsaglia and Tsang, 2000): the bell is cut into 128
// layers of equal area, and a draw is one 32-bit engine call, a comparison
// and a multiply 99 % of the time (std::normal_distribution takes a
// logarithm, a square root and 1.27 engine calls per draw). The engine's
// low 7 bits pick the layer and its high 25 the signed position, so the two
// are independent. Deterministic for a seeded engine.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

namespace canhil::vision_emu {

class Gaussian {
 public:
  /// Draws with mean 0 and standard deviation `sigma`.
  explicit Gaussian(float sigma) noexcept : sigma_(sigma) {}

  /// One draw; `Engine` gives 32 uniform bits (NoiseEngine, std::mt19937).
  template <class Engine>
  float operator()(Engine& engine) const {
    return sigma_ * standard(engine);
  }

  /// A draw of the standard normal distribution. The common case (99 %) is
  /// inline; the wedges and the tail are not, so that the caller's loop stays small.
  template <class Engine>
  static float standard(Engine& engine) {
    static_assert(Engine::min() == 0 && Engine::max() == 0xFFFFFFFFu, "needs an engine of 32 uniform bits");
    const Tables& t = kTables;
    const auto u = static_cast<std::uint32_t>(engine());
    const std::size_t layer = u & 127u;
    const std::int32_t at = static_cast<std::int32_t>(u) >> 7;  // -2^24 .. 2^24 - 1
    const std::int32_t size = at < 0 ? -at : at;
    if (size < t.inside[layer]) [[likely]] {
      return static_cast<float>(at) * t.width[layer];  // wholly under the curve
    }
    return beyond(engine, layer, at);
  }

 private:
  static constexpr float kTailStart = 3.442619855899f;  // where the base layer's tail begins
  struct Tables {
    std::array<std::int32_t, 128> inside;  // |position| below this: under the curve
    std::array<float, 128> width;          // x per unit of position
    std::array<float, 128> height;         // the curve at the layer's outer edge
  };
  static const Tables& tables() noexcept;
  static inline const Tables& kTables = tables();  // built once, at start-up

  // A draw that fell outside its layer's rectangle: the wedge or the tail,
  // and a fresh draw when it is rejected.
  template <class Engine>
  [[gnu::noinline]] static float beyond(Engine& engine, std::size_t layer, std::int32_t at) {
    const Tables& t = kTables;
    for (;;) {
      const float x = static_cast<float>(at) * t.width[layer];
      if (layer == 0) return tail(engine, at < 0);
      // The wedge between the layer's rectangle and the curve.
      if (t.height[layer] + uniform(engine) * (t.height[layer - 1] - t.height[layer]) < std::exp(-0.5f * x * x)) {
        return x;
      }
      const auto u = static_cast<std::uint32_t>(engine());
      layer = u & 127u;
      at = static_cast<std::int32_t>(u) >> 7;
      const std::int32_t size = at < 0 ? -at : at;
      if (size < t.inside[layer]) return static_cast<float>(at) * t.width[layer];
    }
  }
  template <class Engine>
  static float uniform(Engine& engine) {  // (0, 1)
    return (static_cast<float>(static_cast<std::uint32_t>(engine()) >> 8) + 0.5f) * 0x1p-24f;
  }
  // Beyond kTailStart: Marsaglia's exponential rejection.
  template <class Engine>
  static float tail(Engine& engine, bool negative) {
    float x = 0;
    float y = 0;
    do {
      x = -std::log(uniform(engine)) / kTailStart;
      y = -std::log(uniform(engine));
    } while (y + y < x * x);
    return negative ? -(kTailStart + x) : kTailStart + x;
  }

  float sigma_;
};

}  // namespace canhil::vision_emu
