// canhil/timing/analysis.hpp — timing and FTT-CAN compliance of a bus trace.
//
// Feed frames in time order (a candump log, a live interface, a virtual-time
// trace); finish() reports, per message of the set: count, intervals (mean,
// min, max) and jitter percentiles against the specified period, missing and
// late frames; FTT compliance (synchronous frames only in ECs whose TM
// schedules them and inside the synchronous window; sporadic frames only in
// the asynchronous window and no faster than their minimum gap); and the bus
// load at the configured bit rate with exact bit stuffing. Pure: no I/O.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "canhil/frames/ftt.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::timing {

struct TimingConfig {
  /// The bus's FTT configuration, the master's own (frames/ftt.hpp): its
  /// elementary cycle places the synchronous window, its bit rate gives the
  /// load. (The TMs carry each EC's window; the guard is not judged.) With
  /// stamps at the end of frame (a timed wire, a real adapter) a sporadic
  /// message's minimum gap is judged less one worst-case frame's wire time:
  /// the stamps move with each frame's wait for the wire.
  frames::FttConfig ftt;
  double late_fraction = 0.10;  ///< late: an interval longer than the period by this fraction ...
  Nanos late_minimum = std::chrono::microseconds(1500);  ///< ... or by this, whichever is larger
  Nanos window_slack{0};                                 ///< tolerance on the windows' edges (real buses: a few us)
  /// Counts and violations only, in constant memory and time per frame (a
  /// whole match): no intervals kept (no mean, extremes or percentiles) and
  /// no bits counted (no bus load).
  bool violations_only = false;
};

enum class ViolationKind : std::uint8_t {
  kLate,           ///< interval longer than the period plus the tolerance
  kMissing,        ///< interval of 1.5 periods or more: frames missing
  kUnscheduled,    ///< synchronous frame in an EC whose TM does not schedule it
  kOutsideWindow,  ///< synchronous frame outside the synchronous window, or sporadic outside the asynchronous one
  kTooSoon,        ///< sporadic frame closer than its minimum gap
  kDuplicate,      ///< a synchronous message twice in one EC
};
const char* kind_name(ViolationKind k) noexcept;

struct Violation {
  Nanos time{0};
  std::string message;
  ViolationKind kind;
  std::string detail;
};

struct MessageTiming {
  std::string name;
  std::uint32_t id = 0;
  frames::FttKind kind = frames::FttKind::kAsync;
  Nanos spec{0};  ///< period (trigger, synchronous) or minimum gap (asynchronous)
  std::uint64_t count = 0;
  Nanos mean{0}, min{0}, max{0};  ///< intervals between consecutive frames
  Nanos p50{0}, p95{0}, p99{0};   ///< jitter: |interval - period| (synchronous and trigger)
  std::map<ViolationKind, std::uint64_t> violations;
  std::vector<Nanos> intervals;
};

/// What makes a capture unfit to judge timing by: a team's CI must not pass on
/// a broken capture (a wrong interface, an empty log, a master not running).
enum class CaptureProblem : std::uint8_t {
  kNoFrames,   ///< nothing at all
  kNoTrigger,  ///< frames, but no trigger message: no EC to judge them by
  kTooShort,   ///< shorter than the longest period of the message set
};

struct TimingReport {
  Nanos start{0}, end{0};
  std::uint64_t frames = 0;
  std::uint64_t unknown = 0;       ///< frames of ids the message set does not know
  std::uint64_t error_frames = 0;  ///< error frames seen (their bits count toward the load)
  std::uint64_t bits = 0;          ///< on the wire, stuffing included
  double bus_load = 0;             ///< bits / (duration x bit rate)
  std::vector<MessageTiming> messages;
  std::vector<Violation> violations;  ///< the first kMaxListed, in time order
  std::uint64_t violation_count = 0;
  static constexpr std::size_t kMaxListed = 1000;
  /// Why the capture cannot show the timing (none: it can); with text saying what to do.
  std::vector<std::pair<CaptureProblem, std::string>> capture_problems;
  Nanos longest_period{0};  ///< the message set's longest synchronous period
  /// No violations (the capture's own problems are apart: see capture_problems).
  bool ok() const noexcept { return violation_count == 0; }
  bool capture_ok() const noexcept { return capture_problems.empty(); }
};

class TimingAnalyzer {
 public:
  TimingAnalyzer(std::shared_ptr<const frames::MessageSet> set, const TimingConfig& config);
  /// Frames must come in time order (the interface's or log's own time).
  void add(const frames::TimedFrame& frame);
  TimingReport finish() const;
  /// Violations so far (what finish() reports as violation_count).
  std::uint64_t violation_count() const noexcept { return report_.violation_count; }

 private:
  struct PerMessage {
    // What every frame reads first, together: a message's entry is visited
    // once a period, its cache lines cold.
    std::uint64_t count = 0;
    Nanos last{0};
    std::uint64_t last_ec = ~0ULL;
    frames::FttInfo ftt;
    Nanos late_after{0};  // a periodic frame is late beyond period + this (config's late_minimum and late_fraction)
    const frames::MessageCodec* codec = nullptr;
    std::vector<Nanos> intervals;
    std::map<ViolationKind, std::uint64_t> violations;
  };
  void violate(PerMessage& m, Nanos t, ViolationKind k, std::string detail);
  void check_capture(TimingReport& r) const;

  std::shared_ptr<const frames::MessageSet> set_;
  TimingConfig config_;
  Nanos gap_slack_{0};                // sporadic gaps between end-of-frame stamps (the constructor)
  std::vector<PerMessage> messages_;  // parallel to the codec's messages
  TimingReport report_;
  bool have_tm_ = false;
  Nanos tm_time_{0};
  frames::Tm tm_;  // the last TM
  std::uint64_t ec_index_ = 0;
};

/// A table for people: one line per message, then the violations.
std::string format_table(const TimingReport& report);
std::string format_json(const TimingReport& report);

}  // namespace canhil::timing
