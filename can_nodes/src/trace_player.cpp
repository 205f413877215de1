#include "canhil/can_nodes/trace_player.hpp"

#include <algorithm>
#include <cmath>

#include "canhil/base/setup_error.hpp"

namespace canhil::can_nodes {

PlaySchedule::PlaySchedule(std::vector<frames::LogEntry> entries, double speed, bool loop)
    : entries_(std::move(entries)), speed_(speed), loop_(loop) {
  if (entries_.empty()) throw SetupError("the trace has no frames to play");
  if (!(std::isfinite(speed_) && speed_ > 0)) throw SetupError("the speed must be above 0");
  std::stable_sort(entries_.begin(), entries_.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  span_ = entries_.back().time - entries_.front().time;
  gap_ = entries_.size() > 1 ? span_ / static_cast<std::int64_t>(entries_.size() - 1) : std::chrono::milliseconds(1);
  if (gap_ <= Nanos{0}) gap_ = std::chrono::microseconds(1);
}

std::optional<PlaySchedule::Due> PlaySchedule::next() {
  if (at_ == entries_.size()) {
    if (!loop_) return std::nullopt;
    at_ = 0;
    ++pass_;
  }
  const frames::LogEntry& e = entries_[at_++];
  const Nanos trace_time = (e.time - entries_.front().time) + static_cast<std::int64_t>(pass_) * (span_ + gap_);
  const Nanos at{static_cast<std::int64_t>(std::llround(static_cast<double>(trace_time.count()) / speed_))};
  return Due{at, &e, pass_};
}

}  // namespace canhil::can_nodes
