// canhil/timing/bus_analysis.hpp — what a whole message set allows, before any
// trace is taken (`canhil timing --analyse`): every frame's wire time; under
// FTT-CAN the schedule the master builds (frames/ftt.hpp, the master's own
// rules), its synchronous windows over the schedule cycle and the utilisation
// test for them, and every sporadic message's worst-case response in the
// asynchronous window; on a bus without a trigger message, the native CAN
// response-time analysis (schedulability.hpp); then the what-if limits: the
// lowest bit rate, the shortest elementary cycle and how many more copies of
// a message still fit.
//
// Synchronous traffic. canhil's master puts every synchronous message due in
// an EC into that EC's window (it never defers one), so the exact test is that
// each EC's window fits the longest synchronous window allowed (LSW; by
// default what the master leaves: the EC less the trigger message and one
// asynchronous frame). The utilisation-based test of Almeida, Pedreiras and
// Fonseca ("The FTT-CAN protocol: why and how", IEEE Transactions on
// Industrial Electronics 49(6), 2002; after Almeida and Fonseca, "Analysis of
// a simple model for non-preemptive blocking-free scheduling", ECRTS 2001) is
// given beside it, for a master that defers by rate monotonic:
//   U = sum C_i / T_i  <  n (2^(1/n) - 1) (LSW - X) / E,
// X the longest synchronous frame (the idle time a frame that does not fit
// leaves at the window's end), E the EC.
//
// Sporadic traffic (Pedreiras and Almeida's analysis of FTT-CAN's
// asynchronous messaging system: fixed priority by identifier, non-preemptive,
// only inside the asynchronous windows). The window of EC k runs from the end
// of the TM to the start of the synchronous window; the shortest over the
// cycle less the idle time inserted at its end (the longest asynchronous
// frame, which is not started unless it fits) is what each EC serves. A
// message's demand in its busy period (the blocking by one lower-priority
// frame, every higher-priority instance queued in it, its own frame) is served
// window after window; the delay from the window's opening is that service
// time, and the response from the moment the message is ready adds the wait
// for the next window (canhil's slaves queue a sporadic message at the next
// TM: at most one EC and the TM's wire time). Its deadline is its minimum gap
// unless the DBC gives one (GenMsgDeadline, ms).
//
// Pure functions.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/frames/dbc.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/timing/schedulability.hpp"

namespace canhil::timing {

/// One message of the set being analysed, from the DBC or an --add.
struct BusMessage {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  std::uint8_t dlc = 8;
  /// FTT role; on a native bus kSync means periodic and kAsync sporadic.
  frames::FttKind kind = frames::FttKind::kAsync;
  int index = -1;     ///< FTT index of a synchronous message
  Nanos period{0};    ///< trigger, synchronous or periodic
  Nanos min_gap{0};   ///< sporadic
  Nanos deadline{0};  ///< 0: the period, or the minimum gap
  /// The period, or a sporadic message's minimum gap.
  Nanos spacing() const noexcept { return kind == frames::FttKind::kAsync ? min_gap : period; }
};

/// The messages of a DBC and whether it is an FTT-CAN bus (it has a trigger
/// message). FTT attributes are read by frames::read_ftt's rules; a native
/// DBC needs GenMsgCycleTime (periodic) or GenMsgDelayTime (sporadic). Throws
/// DbcError naming the message and the attribute to set.
struct BusSet {
  std::vector<BusMessage> messages;
  bool ftt = false;
};
BusSet read_bus_set(const frames::Database& db);

/// Parses an --add "NAME ID DLC PERIOD_MS sync|async" (ID decimal or 0x hex,
/// above 0x7FF an extended identifier; PERIOD_MS the period of a synchronous
/// message, the minimum gap of a sporadic one) and adds it to `set`: a
/// synchronous message takes the lowest free FTT index. Throws SetupError
/// naming the field that is wrong, or the clash with a message of the set.
void add_message(BusSet& set, std::string_view text);

struct AnalysisConfig {
  frames::FttConfig ftt;  ///< EC, bit rate (also a native bus's), synchronous window guard
  /// The longest synchronous window allowed (LSW); none: what the master
  /// leaves, the EC less the TM and one asynchronous frame.
  std::optional<Nanos> sync_window;
  /// Messages whose extra copies the what-if counts; empty: every message of
  /// a set of at most kDefaultCopies messages (`canhil timing --analyse` puts
  /// every --add here, so that the what-if counts the messages being tried).
  std::vector<std::string> copies_of;
  static constexpr std::size_t kDefaultCopies = 32;
  bool what_if = true;
};

struct FrameRow {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  std::uint8_t dlc = 0;
  frames::FttKind kind = frames::FttKind::kAsync;
  FrameTime time;
};

struct EcLoad {
  std::uint64_t ec = 0;
  std::uint32_t bitmap = 0;
  Nanos window{0};  ///< synchronous window, guard included (0: nothing due)
};

struct SyncBound {
  std::string name;
  std::uint32_t id = 0;
  int index = -1;
  Nanos period{0};
  Nanos wire{0};
  /// Latest end of its frame after its window opened, over every EC it is due
  /// in (the frames due in one EC go in arbitration order).
  Nanos worst_offset{0};
  std::uint64_t worst_ec = 0;
  Nanos longest_window{0};  ///< the longest window it is in
  bool fits = false;        ///< that window fits the LSW
  /// Shortest and longest interval between consecutive frames: the period, as
  /// the windows' starts (at the EC's end less the window) move from one of
  /// its ECs to the next, give or take its end in each window.
  Nanos interval_low{0};
  Nanos interval_high{0};
};

struct SyncAnalysis {
  std::uint64_t cycle_ecs = 0;  ///< the schedule cycle, in ECs
  std::vector<EcLoad> ecs;      ///< every EC of the cycle (the first kMostListed when longer)
  static constexpr std::size_t kMostListed = 4096;
  std::uint64_t worst_ec = 0;
  Nanos longest_window{0};
  Nanos allowed_window{0};  ///< LSW
  Nanos guard{0};
  bool fits = false;  ///< every EC's window fits the LSW (the exact test of canhil's master)
  double utilisation = 0;
  Nanos longest_frame{0};         ///< X
  double utilisation_bound = 0;   ///< n (2^(1/n) - 1) (LSW - guard - X) / E
  bool utilisation_test = false;  ///< utilisation < bound
  std::vector<SyncBound> messages;
};

struct AsyncBound {
  std::string name;
  std::uint32_t id = 0;
  bool extended = false;
  Nanos wire{0};
  Nanos min_gap{0};
  Nanos deadline{0};
  Nanos blocking{0};
  /// Worst delay from its window's opening to the end of its frame (kNever: unbounded).
  Nanos from_window{0};
  Nanos worst_response{0};  ///< from ready: the wait for the next window, then from_window
  int windows = 0;          ///< asynchronous windows that service spans
  bool schedulable = false;
  Nanos margin() const noexcept { return deadline - worst_response; }
};

struct AsyncAnalysis {
  Nanos shortest_window{0};          ///< the shortest asynchronous window of the cycle
  Nanos idle_inserted{0};            ///< the longest asynchronous frame: not started unless it fits
  Nanos usable{0};                   ///< served each EC: shortest window less the idle time
  Nanos wait{0};                     ///< longest wait from ready to the next window's opening
  double share = 0;                  ///< usable / EC
  double utilisation = 0;            ///< sum wire / minimum gap
  std::vector<AsyncBound> messages;  ///< priority order
};

struct CopiesLimit {
  std::string name;
  int copies = 0;       ///< more copies that still leave the set schedulable
  std::string limited;  ///< what stopped the count ("schedulability", "free FTT indices", ...)
};

struct WhatIf {
  std::uint32_t lowest_bit_rate = 0;  ///< 0: none up to kHighestBitRate
  Nanos shortest_ec{0};               ///< 0: none (FTT only)
  std::vector<CopiesLimit> copies;
  static constexpr std::uint32_t kLowestBitRate = 10'000;
  static constexpr std::uint32_t kHighestBitRate = 1'000'000;
};

/// A message that misses, and by how much (kNever: unbounded).
struct Miss {
  std::string name;
  Nanos by{0};
  std::string why;
};

struct BusAnalysis {
  bool ftt = false;
  AnalysisConfig config;
  std::vector<FrameRow> frames;  ///< in priority order
  SyncAnalysis sync;             ///< FTT
  AsyncAnalysis async;           ///< FTT
  NativeAnalysis native;         ///< native CAN
  std::string misfit;            ///< the master's refusal (FttSchedule::misfit), if any
  WhatIf what_if;
  std::vector<Miss> misses;
  bool schedulable() const noexcept { return misses.empty(); }
};

/// Analyses `set` (with what-if unless config.what_if is false). Throws
/// SetupError for what no bus can carry (a period that is not a whole number
/// of ECs, two messages on one identifier, a frame longer than 8 bytes).
BusAnalysis analyse_bus(const BusSet& set, const AnalysisConfig& config);

std::string format_analysis(const BusAnalysis& a);
std::string format_analysis_json(const BusAnalysis& a);
/// One picture: under FTT-CAN the ECs of one schedule cycle as time lines
/// (the TM, the asynchronous window with every sporadic frame at once in the
/// worst EC, the synchronous window with its frames as bars), the worst EC
/// marked; on a native bus each message's worst-case response against its
/// deadline.
std::string format_analysis_svg(const BusAnalysis& a);

}  // namespace canhil::timing
