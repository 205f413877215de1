// canhil/frames/ftt_slot.hpp — an FTT-CAN slave's synchronous slot: from the
// trigger messages it hears, when its synchronous messages are due. The
// synchronous window sits at the end of the elementary cycle (EC) and the TM
// carries its length, so a producer sends at TM time + EC - window. The one
// rule for every slave: the emulated nodes, the reference handler and the
// tests' laptop endpoint. Pure; one per producer, not thread-safe.
#pragma once

#include <cstdint>
#include <optional>

#include "canhil/base/time.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::frames {

/// The start of the synchronous window of the EC a TM received at `tm_time` opens.
constexpr Nanos sync_window_start(const Tm& tm, Nanos tm_time, Nanos ec) noexcept {
  return tm_time + ec - std::chrono::microseconds(tm.sync_window_us);
}

class SyncSlot {
 public:
  /// Notes the TM; returns the window start when any of `mine` (sync_bitmap
  /// bits, FTT indices) is due in this EC, else nothing.
  std::optional<Nanos> on_tm(const Tm& tm, Nanos tm_time, Nanos ec, std::uint32_t mine) noexcept {
    due_ = tm.sync_bitmap & mine;
    start_ = sync_window_start(tm, tm_time, ec);
    if (due_ == 0) return std::nullopt;
    return start_;
  }
  /// The message with FTT index `ftt_index` is due in this EC.
  bool due(int ftt_index) const noexcept { return ((due_ >> ftt_index) & 1u) != 0; }
  /// Something is due and its window has opened by `now`.
  bool pending(Nanos now) const noexcept { return due_ != 0 && now >= start_; }
  /// When the window opens (with something due), else kNever.
  Nanos when() const noexcept { return due_ != 0 ? start_ : kNever; }
  /// Everything due was sent.
  void done() noexcept { due_ = 0; }

 private:
  std::uint32_t due_ = 0;
  Nanos start_{0};
};

}  // namespace canhil::frames
