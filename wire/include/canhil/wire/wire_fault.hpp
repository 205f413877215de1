// canhil/wire/wire_fault.hpp — faults at the bus's level, by rule, and the
// seeded draws that decide which frames they hit.
//
// A rule holds from `from` to `until` (bus time). What each kind does
// (docs/faults.md has the language that writes them):
//   kBitErrors     every bit on the wire flips with probability `rate`
//   kFrameErrors   each frame matched (by `id`, by the sending `controller`,
//                  or every frame) is hit with probability `rate` (1: every
//                  one), at a bit drawn between SOF and the CRC's end
//   kNoAck         frames matched are not acknowledged: an ACK error
//   kStuckDominant a node holds the bus dominant: nothing gets through, every
//                  controller's counters climb (transmitters to bus-off)
//   kBabbling      `controller` sends `babble` back to back, ahead of its own queue
//   kCut           `controller` is off the bus (a cut cable): nobody gets its
//                  frames, it gets none and sees its own go unacknowledged
//   kBusOff        `controller` goes bus-off at `from`
// Pure: the draws come from the seed, in the order frames are asked about.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/frames/wire.hpp"

namespace canhil::wire {

using ControllerId = std::uint32_t;

struct FaultRule {
  enum class Kind : std::uint8_t { kBitErrors, kFrameErrors, kNoAck, kStuckDominant, kBabbling, kCut, kBusOff };
  Kind kind = Kind::kFrameErrors;
  Nanos from{0};
  Nanos until = kNever;
  double rate = 1.0;                       ///< kBitErrors: per bit; kFrameErrors: per frame matched
  std::optional<std::uint32_t> id;         ///< kFrameErrors, kNoAck: only frames of this identifier
  std::optional<ControllerId> controller;  ///< who: the sender matched, or the node the fault is in
  frames::WireFrame babble;                ///< kBabbling: the frame sent back to back
};
/// "bit-errors", "frame-errors", "no-ack", "stuck-dominant", "babbling", "cut", "bus-off".
const char* fault_kind_name(FaultRule::Kind kind) noexcept;

/// How a frame on the wire ends.
struct ErrorPlan {
  enum class Cause : std::uint8_t {
    kNone,  ///< it gets through
    kBit,   ///< a bit flipped between SOF and the CRC's end: the transmitter's bit error, the receivers' stuff error
    kForm,  ///< a bit flipped in a fixed-form field (CRC delimiter, ACK delimiter, end of frame)
    kAck,   ///< nobody acknowledged it
  };
  Cause cause = Cause::kNone;
  std::uint32_t bit = 0;  ///< where it is seen (SOF = 0)
};

class Faults {
 public:
  explicit Faults(std::uint64_t seed) : rng_(seed) {}
  /// A rule from `rule.from` (not before `now`: a rule cannot start in the past).
  void add(FaultRule rule, Nanos now);
  /// Every rule that has not ended ends at `now`.
  void clear(Nanos now);
  const std::vector<FaultRule>& rules() const noexcept { return rules_; }

  /// How a frame of `total_bits` (intermission included) sent by `from`,
  /// starting at `start`, ends; `receivers` whether any other controller on
  /// the bus would acknowledge it.
  ErrorPlan plan(const frames::WireFrame& frame, ControllerId from, Nanos start, std::uint32_t total_bits,
                 bool receivers);
  // Asked for every controller at every event: a bus without rules answers
  // at once.
  bool cut(ControllerId controller, Nanos t) const noexcept { return !rules_.empty() && cut_by_rule(controller, t); }
  /// The stuck-dominant rule holding at `t`, if any.
  const FaultRule* stuck(Nanos t) const noexcept { return rules_.empty() ? nullptr : stuck_by_rule(t); }
  const FaultRule* babbling(ControllerId controller, Nanos t) const noexcept {
    return rules_.empty() ? nullptr : babbling_by_rule(controller, t);
  }
  /// The earliest start or end of a rule not yet taken (kNever: none).
  Nanos next_change() const noexcept { return rules_.empty() ? kNever : next_change_of_rules(); }
  /// The rules starting at `at` not yet taken, marked taken; likewise ending.
  std::vector<const FaultRule*> take_starts(Nanos at);
  std::vector<const FaultRule*> take_ends(Nanos at);

 private:
  bool cut_by_rule(ControllerId controller, Nanos t) const noexcept;
  const FaultRule* stuck_by_rule(Nanos t) const noexcept;
  const FaultRule* babbling_by_rule(ControllerId controller, Nanos t) const noexcept;
  Nanos next_change_of_rules() const noexcept;
  struct Taken {
    bool started = false;
    bool ended = false;
  };
  double uniform() noexcept { return static_cast<double>(rng_() >> 11) * 0x1.0p-53; }  // [0, 1)
  std::vector<FaultRule> rules_;  // first: asked whether it is empty for every frame
  std::vector<Taken> taken_;
  std::mt19937_64 rng_;
};

}  // namespace canhil::wire
