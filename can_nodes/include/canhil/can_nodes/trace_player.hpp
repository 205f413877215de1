// canhil/can_nodes/trace_player.hpp — when each frame of a recorded bus is
// due when it is played again (`canhil play`): frame i at (t_i - t_0) / speed
// after the start, every deadline absolute from the start (a late send does
// not push the rest back); with a loop, each pass starts one mean frame gap
// after the last frame of the one before.
#pragma once

#include <optional>
#include <vector>

#include "canhil/frames/candump.hpp"

namespace canhil::can_nodes {

class PlaySchedule {
 public:
  /// `entries` in time order (sorted here if not); speed > 0; SetupError for none or a bad speed.
  PlaySchedule(std::vector<frames::LogEntry> entries, double speed, bool loop);

  struct Due {
    Nanos at{0};  ///< after the start
    const frames::LogEntry* entry = nullptr;
    std::uint64_t pass = 0;  ///< 0 for the first time through
  };
  /// The next frame and when it is due, or nullopt at the end (never with a loop).
  std::optional<Due> next();

  std::size_t size() const noexcept { return entries_.size(); }
  /// One pass, in trace time (the last frame's time after the first's).
  Nanos span() const noexcept { return span_; }

 private:
  std::vector<frames::LogEntry> entries_;
  double speed_;
  bool loop_;
  Nanos span_{0}, gap_{0};
  std::size_t at_ = 0;
  std::uint64_t pass_ = 0;
};

}  // namespace canhil::can_nodes
