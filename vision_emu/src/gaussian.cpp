#include "canhil/vision_emu/gaussian.hpp"

namespace canhil::vision_emu {

// Layer 0 is the base: a rectangle of the layers' common area up to
// kTailStart and the tail beyond it. Layers 1..127 are stacked above it,
// layer 127 lowest (outer edge at kTailStart), layer 1 at the top.
const Gaussian::Tables& Gaussian::tables() noexcept {
  static const Tables t = [] {
    constexpr double kScale = 0x1p24;              // positions run over +-2^24
    constexpr double kArea = 9.91256303526217e-3;  // each layer's, for exp(-x^2 / 2)
    const auto bell = [](double x) { return std::exp(-0.5 * x * x); };
    Tables out{};
    double edge = kTailStart;
    const double base_width = kArea / bell(edge);  // the base rectangle reaches past the tail's start
    out.inside[0] = static_cast<std::int32_t>(edge / base_width * kScale);
    out.width[0] = static_cast<float>(base_width / kScale);
    out.height[0] = 1.0f;
    out.inside[1] = 0;
    out.width[127] = static_cast<float>(edge / kScale);
    out.height[127] = static_cast<float>(bell(edge));
    for (std::size_t i = 126; i >= 1; --i) {
      const double next = std::sqrt(-2.0 * std::log(kArea / edge + bell(edge)));
      out.inside[i + 1] = static_cast<std::int32_t>(next / edge * kScale);
      edge = next;
      out.height[i] = static_cast<float>(bell(edge));
      out.width[i] = static_cast<float>(edge / kScale);
    }
    return out;
  }();
  return t;
}

}  // namespace canhil::vision_emu
