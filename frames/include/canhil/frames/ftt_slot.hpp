// canhil/frames/ftt_slot.hpp — an FTT-CAN slave's slots: from the trigger
// messages it hears, when its synchronous messages are due and when its
// asynchronous (sporadic) ones may go. The synchronous window sits at the end
// of the elementary cycle (EC) and the TM carries its length, so a producer
// sends at TM time + EC - window. The asynchronous window lies between: it
// opens when the TM has left the wire and closes where the synchronous window
// starts; a sporadic message goes in it no sooner than its minimum gap after
// the previous one. The one copy of these rules, for every slave (the
// emulated nodes, the reference handler, the tests' laptop endpoint) and for
// the timing analysis that judges them. Pure; SyncSlot is one per producer,
// not thread-safe. The master's side (the schedule) is ftt.hpp.
#pragma once

#include <cstdint>
#include <optional>

#include "canhil/base/time.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::frames {

/// The start of the EC a TM opens, from its stamp (`config.stamps`): the
/// stamp itself, or, stamped at its end of frame, as much earlier as the TM's
/// own bits up to its end of frame take at `config.bit_rate`. Every "TM time"
/// below is this start.
Nanos ec_start(const CanFrame& tm, Nanos stamp, const FttConfig& config) noexcept;

/// The start of the synchronous window of the EC a TM received at `tm_time` opens.
constexpr Nanos sync_window_start(const Tm& tm, Nanos tm_time, Nanos ec) noexcept {
  return tm_time + ec - std::chrono::microseconds(tm.sync_window_us);
}

/// Whether a sporadic message at `at` keeps its minimum gap after the
/// previous one at `last`.
constexpr bool keeps_min_gap(Nanos at, Nanos last, Nanos min_gap) noexcept { return at - last >= min_gap; }

/// A sporadic message's slot in the EC a TM sent at `tm_time` opens: when the
/// TM has left the wire (`tm_wire_time` later), if by the TM its minimum gap
/// has passed since it last went (`last_sent`); else kNever (a later EC).
constexpr Nanos async_slot(Nanos tm_time, Nanos tm_wire_time, Nanos last_sent, Nanos min_gap) noexcept {
  return keeps_min_gap(tm_time, last_sent, min_gap) ? tm_time + tm_wire_time : kNever;
}

/// Where the asynchronous window of the EC a TM received at `tm_time` opens
/// ends: at the synchronous window's start; never (kNever) when the TM
/// schedules no synchronous window, the whole EC being asynchronous.
constexpr Nanos async_window_end(const Tm& tm, Nanos tm_time, Nanos ec) noexcept {
  return tm.sync_window_us == 0 ? kNever : sync_window_start(tm, tm_time, ec);
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
