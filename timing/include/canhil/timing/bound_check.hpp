// canhil/timing/bound_check.hpp — a trace against its analysis: every
// quantity the analysis bounds, observed frame by frame, next to its bound.
//
// Under FTT-CAN: the trigger message's interval (the EC); a synchronous
// frame's end in its window (from the window's start, which the TM carries, to
// the frame's time stamp: at most the latest end the analysis gives for that
// message, and never before the window opens) and its interval (the period,
// as the window's start moves from one of its ECs to the next, give or take
// its end in each: SyncBound::interval_low and _high); a sporadic frame's delay after the
// asynchronous window opened (the TM off the wire), at most its bound from the
// window's opening. On a native bus: a periodic message's interval, at most
// its period plus its worst-case response less its best-case frame time.
//
// An observation beyond its bound is a violation, with the frame's time:
// either the emulation or the analysis is wrong. `slack` widens every bound
// (a real bus's clocks; 0 for a virtual-time trace). Frames in time order.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "canhil/frames/frame.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/timing/bus_analysis.hpp"

namespace canhil::timing {

enum class Bounded : std::uint8_t {
  kInterval,     ///< between consecutive frames of a periodic message (or TMs)
  kEndInWindow,  ///< synchronous: frame time less its window's start
  kAfterOpen,    ///< sporadic: frame time less the asynchronous window's opening
};
const char* bounded_name(Bounded q) noexcept;

struct Observation {
  std::string message;
  Bounded quantity = Bounded::kInterval;
  Nanos low{0};   ///< the bound's lower end (kInterval, kEndInWindow: 0)
  Nanos high{0};  ///< the bound
  std::uint64_t count = 0;
  Nanos least{kNever};
  Nanos most{0};
  Nanos most_at{0};  ///< the frame time of the largest
  std::uint64_t outside = 0;
};

struct BoundViolation {
  Nanos time{0};
  std::string message;
  Bounded quantity = Bounded::kInterval;
  Nanos observed{0};
  Nanos low{0}, high{0};
};

struct BoundReport {
  std::uint64_t frames = 0;
  std::vector<Observation> observations;
  std::vector<BoundViolation> violations;  ///< the first kMostListed
  std::uint64_t violation_count = 0;
  static constexpr std::size_t kMostListed = 100;
  bool ok() const noexcept { return violation_count == 0; }
};

class BoundChecker {
 public:
  /// `set` decodes the TMs of an FTT-CAN trace (nullptr on a native bus).
  BoundChecker(const BusAnalysis& analysis, std::shared_ptr<const frames::MessageSet> set, Nanos slack);
  void add(const frames::TimedFrame& f);
  BoundReport finish() const { return report_; }

 private:
  struct Watch {
    frames::FttKind kind = frames::FttKind::kAsync;
    std::size_t interval = ~std::size_t{0};  // index into observations, if bounded
    std::size_t in_window = ~std::size_t{0};
    Nanos last{kNever};
  };
  std::size_t observe(const std::string& name, Bounded q, Nanos low, Nanos high);
  void note(std::size_t obs, Nanos value, Nanos at);

  std::shared_ptr<const frames::MessageSet> set_;
  Nanos slack_;
  Nanos ec_{0};
  frames::FttConfig ftt_;
  Nanos tm_wire_{0};
  std::map<std::uint64_t, Watch> watch_;  // by (extended << 32 | id)
  bool have_tm_ = false;
  Nanos window_start_{0};
  Nanos async_open_{0};
  BoundReport report_;
};

std::string format_bounds(const BoundReport& r);
std::string format_bounds_json(const BoundReport& r);

}  // namespace canhil::timing
