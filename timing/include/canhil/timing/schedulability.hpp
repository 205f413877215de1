// canhil/timing/schedulability.hpp — what a message set allows before any
// trace is taken: every message's wire time, and the worst-case response time
// of every message on a native CAN bus (fixed priority by identifier,
// non-preemptive, no errors).
//
// The response-time analysis is the revised one of Davis, Burns, Bril and
// Lukkien, "Controller Area Network (CAN) schedulability analysis: refuted,
// revisited and revised", Real-Time Systems 35 (2007): a message can be
// blocked once by a lower-priority frame already on the wire, is delayed by
// every higher-priority frame queued before its own arbitration (one bit time
// after it is queued), and the worst case may be any instance inside the
// longest busy period of its priority level, not only the first (the flaw
// that paper found in the 1994 analysis). Response time: from queuing (the
// period's start plus the message's queuing jitter) to the end of its frame.
//
// Wire times are frames/wire.hpp's, the interframe space included: a standard
// frame of 8 data bytes takes 111 bits at best and 135 at worst (every stuff
// bit the rules allow). Pure functions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canhil/base/time.hpp"

namespace canhil::timing {

/// A frame's time on the wire at a bit rate, best case (no stuff bit) and
/// worst case (the most stuff bits its length allows).
struct FrameTime {
  std::uint32_t best_bits = 0;
  std::uint32_t worst_bits = 0;
  Nanos best{0};
  Nanos worst{0};
};

/// Throws SetupError for more than 8 data bytes or a bit rate of 0.
FrameTime frame_time(std::uint32_t data_bytes, bool extended, std::uint32_t bit_rate_bps);

/// One message as the analysis sees it: its priority (the identifier), its
/// worst-case transmission time, how often it may be queued and by when it
/// must be through.
struct AnalysedMessage {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  Nanos transmission{0};  ///< worst-case wire time (FrameTime::worst, or a figure of one's own)
  Nanos period{0};        ///< period, or a sporadic message's minimum gap; > 0
  Nanos deadline{0};      ///< from queuing; 0: the period
  Nanos jitter{0};        ///< queuing jitter: how much later than its period's start it may be queued
};

/// Arbitration order: true when `a` wins over `b` (the lower identifier; at an
/// equal 11-bit base, the standard frame wins over the extended one).
bool wins_arbitration(const AnalysedMessage& a, const AnalysedMessage& b) noexcept;

struct ResponseBound {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  Nanos transmission{0};
  Nanos period{0};
  Nanos deadline{0};  ///< the one judged against (the period when none was given)
  Nanos blocking{0};  ///< longest lower-priority frame that can hold the bus when it is queued
  /// Longest busy period of its priority level; kNever when the messages of
  /// its priority and above need the whole bus (utilisation >= 1).
  Nanos busy_period{0};
  int instances = 0;         ///< instances inside that busy period, every one analysed
  int worst_instance = 0;    ///< which of them (0: the first) has the worst response
  Nanos worst_response{0};   ///< kNever when unbounded
  bool schedulable = false;  ///< worst_response <= deadline
  Nanos margin() const noexcept { return deadline - worst_response; }  ///< negative: misses by that much
};

struct NativeAnalysis {
  std::uint32_t bit_rate_bps = 0;
  Nanos bit_time{0};
  double utilisation = 0;               ///< sum of transmission / period
  std::vector<ResponseBound> messages;  ///< in priority order, highest first
  bool schedulable() const noexcept;
};

/// The revised analysis for every message. Throws SetupError naming the
/// message when a period or transmission time is not positive or two messages
/// share an identifier (they would collide in arbitration).
NativeAnalysis analyse_native_can(std::vector<AnalysedMessage> messages, std::uint32_t bit_rate_bps);

/// The same with an explicit bit time (the time added before arbitration;
/// analyses in the literature often give times in units of their own).
NativeAnalysis analyse_native_can(std::vector<AnalysedMessage> messages, Nanos bit_time);

}  // namespace canhil::timing
