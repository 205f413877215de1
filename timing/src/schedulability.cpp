#include "canhil/timing/schedulability.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/wire.hpp"
#include "units.hpp"

namespace canhil::timing {
namespace {

// A busy period longer than this is taken as unbounded: it only happens when
// the utilisation is within a hair of 1, and no bus is designed there.
constexpr Nanos kLongestBusyPeriod = std::chrono::hours(1);

using units::ceil_div;

// Data frames (frames/wire.hpp's order).
std::uint64_t arbitration_key(const AnalysedMessage& m) noexcept { return frames::arbitration_key(m.id, m.extended); }

std::string name_of(const AnalysedMessage& m) {
  char id[16];
  std::snprintf(id, sizeof id, m.extended ? "0x%08X" : "0x%03X", m.id);
  return (m.name.empty() ? std::string("message") : m.name) + " (" + id + ")";
}

// Interference of the messages before `end` in `set` over a window `w`, each
// queued at most ceil((w + jitter + extra) / period) times.
Nanos interference(const std::vector<AnalysedMessage>& set, std::size_t end, Nanos w, Nanos extra) noexcept {
  Nanos total{0};
  for (std::size_t k = 0; k < end; ++k)
    total += ceil_div(w + set[k].jitter + extra, set[k].period) * set[k].transmission;
  return total;
}

ResponseBound bound(const std::vector<AnalysedMessage>& set, std::size_t m, Nanos bit_time, double level_utilisation) {
  const AnalysedMessage& msg = set[m];
  ResponseBound r;
  r.name = msg.name;
  r.id = msg.id;
  r.extended = msg.extended;
  r.transmission = msg.transmission;
  r.period = msg.period;
  r.deadline = msg.deadline > Nanos{0} ? msg.deadline : msg.period;
  for (std::size_t k = m + 1; k < set.size(); ++k) r.blocking = std::max(r.blocking, set[k].transmission);
  if (level_utilisation >= 1.0) {
    r.busy_period = r.worst_response = kNever;
    return r;
  }
  // The longest busy period of level m: blocking, then everything of priority
  // m and above queued in it (Davis et al. 2007, the busy period t_m).
  Nanos t = msg.transmission;
  for (;;) {
    const Nanos next = r.blocking + interference(set, m + 1, t, Nanos{0});
    if (next > kLongestBusyPeriod) {
      r.busy_period = r.worst_response = kNever;
      return r;
    }
    if (next == t) break;
    t = next;
  }
  r.busy_period = t;
  r.instances = static_cast<int>(std::max<std::int64_t>(1, ceil_div(t + msg.jitter, msg.period)));
  // Each instance q: its queuing delay w(q) (the higher-priority frames queued
  // up to one bit time after its own queuing, q earlier instances of itself
  // and the blocking), then R(q) = J + w(q) - q T + C.
  for (int q = 0; q < r.instances; ++q) {
    const Nanos own = q * msg.transmission;
    Nanos w = r.blocking + own;
    for (;;) {
      const Nanos next = r.blocking + own + interference(set, m, w, bit_time);
      if (next == w) break;
      w = next;
    }
    const Nanos response = msg.jitter + w - q * msg.period + msg.transmission;
    if (response > r.worst_response) {
      r.worst_response = response;
      r.worst_instance = q;
    }
  }
  r.schedulable = r.worst_response <= r.deadline;
  return r;
}

}  // namespace

FrameTime frame_time(std::uint32_t data_bytes, bool extended, std::uint32_t bit_rate_bps) {
  if (data_bytes > 8)
    throw SetupError("a classic CAN frame carries 0 to 8 data bytes, not " + std::to_string(data_bytes));
  if (bit_rate_bps == 0) throw SetupError("the bit rate must be positive");
  FrameTime f;
  f.best_bits = frames::best_case_frame_bits(static_cast<std::uint8_t>(data_bytes), extended);
  f.worst_bits = frames::worst_case_frame_bits(static_cast<std::uint8_t>(data_bytes), extended);
  f.best = frames::bits_to_time(f.best_bits, bit_rate_bps);
  f.worst = frames::bits_to_time(f.worst_bits, bit_rate_bps);
  return f;
}

bool wins_arbitration(const AnalysedMessage& a, const AnalysedMessage& b) noexcept {
  return arbitration_key(a) < arbitration_key(b);
}

bool NativeAnalysis::schedulable() const noexcept {
  return std::all_of(messages.begin(), messages.end(), [](const ResponseBound& m) { return m.schedulable; });
}

NativeAnalysis analyse_native_can(std::vector<AnalysedMessage> messages, std::uint32_t bit_rate_bps) {
  if (bit_rate_bps == 0) throw SetupError("the bit rate must be positive");
  NativeAnalysis a = analyse_native_can(std::move(messages), frames::bits_to_time(1, bit_rate_bps));
  a.bit_rate_bps = bit_rate_bps;
  return a;
}

NativeAnalysis analyse_native_can(std::vector<AnalysedMessage> messages, Nanos bit_time) {
  for (const AnalysedMessage& m : messages) {
    if (m.period <= Nanos{0}) {
      throw SetupError(name_of(m) + " has no period: give its period (or, if sporadic, its minimum gap)");
    }
    if (m.transmission <= Nanos{0}) throw SetupError(name_of(m) + " has no transmission time");
    if (m.jitter < Nanos{0} || m.deadline < Nanos{0}) throw SetupError(name_of(m) + ": jitter and deadline are >= 0");
  }
  std::stable_sort(messages.begin(), messages.end(), wins_arbitration);
  for (std::size_t i = 1; i < messages.size(); ++i) {
    if (arbitration_key(messages[i - 1]) == arbitration_key(messages[i])) {
      throw SetupError(name_of(messages[i - 1]) + " and " + name_of(messages[i]) +
                       " share an identifier: two senders of one identifier collide in arbitration");
    }
  }
  NativeAnalysis a;
  a.bit_time = bit_time;
  double level = 0;
  for (std::size_t m = 0; m < messages.size(); ++m) {
    level += to_seconds(messages[m].transmission) / to_seconds(messages[m].period);
    a.messages.push_back(bound(messages, m, bit_time, level));
  }
  a.utilisation = level;
  return a;
}

}  // namespace canhil::timing
