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

/// What a received frame's time stamp marks: its first bit (an instant bus
/// such as vcan, where writing a frame is sending it, or a controller's
/// start-of-frame stamp) or its end of frame (a controller's receive stamp:
/// a real can0, canhil's timed wire). A slave takes the EC's start from the
/// TM's stamp accordingly (ftt_slot.hpp, ec_start).
enum class StampAt : std::uint8_t { kStartOfFrame, kEndOfFrame };

struct FttConfig {
  Nanos elementary_cycle = 10ms;
  std::uint32_t bit_rate = 1'000'000;  ///< for wire times (on an instant bus too)
  Nanos sync_window_guard = 20us;      ///< added to every synchronous window
  StampAt stamps = StampAt::kStartOfFrame;
};

/// One message as the master's rules see it: what it is, its FTT index and
/// period (synchronous), and its worst-case wire time at the bus's bit rate.
struct FttEntry {
  std::string name;
  FttKind kind = FttKind::kAsync;
  int index = -1;   ///< synchronous: its bit of TM.sync_bitmap
  Nanos period{0};  ///< trigger and synchronous
  Nanos wire{0};    ///< worst-case wire time (bit stuffing, interframe space)
};

class FttSchedule {
 public:
  /// What to do when the busiest EC does not fit (TM + one asynchronous frame
  /// + its synchronous window): refuse (a master about to run) or build the
  /// schedule anyway and say why in misfit() (an analysis judging the set).
  enum class Fit : std::uint8_t { kRequire, kReport };

  /// Throws SetupError when a period is not a whole number of ECs or the
  /// busiest EC does not fit.
  FttSchedule(const MessageSet& set, const FttConfig& config);
  /// The same rules for messages of one's own (a set being designed). Throws
  /// SetupError for a period that is not a whole number of ECs, a trigger
  /// period other than the EC or an index outside 0..31; a misfit only with
  /// Fit::kRequire.
  FttSchedule(const std::vector<FttEntry>& entries, const FttConfig& config, Fit fit = Fit::kRequire);
  /// The message set's messages as the master sees them at a bit rate.
  static std::vector<FttEntry> entries(const MessageSet& set, std::uint32_t bit_rate);

  const FttConfig& config() const noexcept { return config_; }
  /// Synchronous messages due in EC `ec_index`, as sync_bitmap bits.
  std::uint32_t bitmap(std::uint64_t ec_index) const noexcept {
    return cycle_bitmaps_.empty() ? due(ec_index) : cycle_bitmaps_[ec_index % cycle_bitmaps_.size()];
  }
  /// Length of the synchronous window for a bitmap.
  Nanos sync_window(std::uint32_t bitmap) const noexcept;

  /// ECs after which the schedule repeats (the least common multiple of the periods, in ECs).
  std::uint64_t cycle_ecs() const noexcept { return cycle_; }
  /// The first EC of the cycle with the longest synchronous window, and that window.
  std::uint64_t worst_ec() const noexcept { return worst_ec_; }
  Nanos longest_sync_window() const noexcept { return longest_window_; }
  Nanos trigger_wire() const noexcept { return tm_time_; }              ///< the TM's worst-case wire time
  Nanos longest_async_wire() const noexcept { return longest_async_; }  ///< the longest asynchronous frame's
  /// Empty when the busiest EC fits; else why not and what to do.
  const std::string& misfit() const noexcept { return misfit_; }
  bool fits() const noexcept { return misfit_.empty(); }

 private:
  // A cycle longer than this (periods with a huge least common multiple) is
  // not tabled: bitmap() then works each EC's out.
  static constexpr std::uint64_t kMostTabled = 1U << 16;
  std::uint32_t due(std::uint64_t ec_index) const noexcept;

  FttConfig config_;
  std::array<std::uint32_t, 32> period_ecs_{};  // 0: no message at this index
  std::array<Nanos, 32> frame_time_{};
  std::vector<std::uint32_t> cycle_bitmaps_;  // bitmap() of each EC of the cycle, the schedule repeating after it
  std::uint64_t cycle_ = 1;
  std::uint64_t worst_ec_ = 0;
  Nanos longest_window_{0};
  Nanos tm_time_{0};
  Nanos longest_async_{0};
  std::string misfit_;
};

}  // namespace canhil::frames
