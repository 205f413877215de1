#include "canhil/can_nodes/bus.hpp"

namespace canhil::can_nodes {
namespace {
constexpr std::uint32_t kEffFlag = 0x8000'0000u;  // CAN_EFF_FLAG
constexpr std::uint32_t kRtrFlag = 0x4000'0000u;  // CAN_RTR_FLAG
}  // namespace

bool Filter::matches(const CanFrame& frame) const noexcept {
  const std::uint32_t rx =
      frame.id | (frame.extended ? kEffFlag : 0u) | (frame.kind == frames::FrameKind::kRemote ? kRtrFlag : 0u);
  const std::uint32_t want = id | (extended ? kEffFlag : 0u) | (remote ? kRtrFlag : 0u);
  const std::uint32_t m = mask | (match_extended ? kEffFlag : 0u) | (match_remote ? kRtrFlag : 0u);
  const bool hit = (rx & m) == (want & m);
  return hit != invert;
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
