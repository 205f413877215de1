// canhil/frames/ftt.hpp — the FTT-CAN configuration and schedule: the
// master's rules, which the master node (can_nodes/) follows and the timing
// analysis (timing/) can judge a capture by. A slave's side is ftt_slot.hpp.
//
// The elementary cycle (EC) is laid out as: trigger message (TM) at its start,
// then the asynchronous window, then the synchronous window at its end, whose
// length the TM carries. A synchronous message with period P is due in every
// EC k with k % (P / EC) == 0; its producer sends it at the start of the
// synchronous window. The window is the worst-case wire time of the frames
// due (bit stuffing included) at the configured bit rate, plus a guard.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/base/time.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::frames {

using namespace std::chrono_literals;

struct FttConfig {
  Nanos elementary_cycle = 10ms;
  std::uint32_t bit_rate = 1'000'000;  ///< for wire times; vcan itself has none
  Nanos sync_window_guard = 20us;      ///< added to every synchronous window
};

class FttSchedule {
 public:
  /// Throws SetupError when a period is not a whole number of ECs or the
  /// busiest EC does not fit (TM + one asynchronous frame + its window).
  FttSchedule(const MessageSet& set, const FttConfig& config);

  const FttConfig& config() const noexcept { return config_; }
  /// Synchronous messages due in EC `ec_index`, as sync_bitmap bits.
  std::uint32_t bitmap(std::uint64_t ec_index) const noexcept {
    return cycle_bitmaps_.empty() ? due(ec_index) : cycle_bitmaps_[ec_index % cycle_bitmaps_.size()];
  }
  /// Length of the synchronous window for a bitmap.
  Nanos sync_window(std::uint32_t bitmap) const noexcept;

 private:
  // A cycle longer than this (periods with a huge least common multiple) is
  // not tabled: bitmap() then works each EC's out.
  static constexpr std::uint64_t kMostTabled = 1U << 16;
  std::uint32_t due(std::uint64_t ec_index) const noexcept;

  FttConfig config_;
  std::array<std::uint32_t, 32> period_ecs_{};  // 0: no message at this index
  std::array<Nanos, 32> frame_time_{};
  std::vector<std::uint32_t> cycle_bitmaps_;  // bitmap() of each EC of the cycle, the schedule repeating after it
};

}  // namespace canhil::frames
