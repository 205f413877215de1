#include "canhil/can_nodes/bus.hpp"

namespace canhil::can_nodes {
bool Filter::matches(const CanFrame& frame) const noexcept {
  const std::uint32_t rx =
      frame.id | (frame.extended ? kEffFlag : 0u) | (frame.kind == frames::FrameKind::kRemote ? kRtrFlag : 0u);
  return hits(rx) != invert;
}

const char* state_name(BusState state) noexcept {
  switch (state) {
    case BusState::kUp:
      return "up";
    case BusState::kDown:
      return "down";
    case BusState::kGone:
      return "gone";
  }
  return "?";
}

}  // namespace canhil::can_nodes
