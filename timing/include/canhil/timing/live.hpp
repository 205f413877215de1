// canhil/timing/live.hpp — a bus measured as it runs: frames, bus load and,
// per periodic message, how far its periods stray from the nominal one, over
// whole windows of bus time (one second by default). What the viewer plots;
// the after-the-fact analysis of a trace is analysis.hpp.
//
// add() costs a lookup and a few additions per frame and allocates nothing.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "canhil/frames/frame.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::timing {

class LiveBusStats {
 public:
  LiveBusStats(std::shared_ptr<const frames::MessageSet> set, std::uint32_t bit_rate,
               Nanos window = std::chrono::seconds(1));

  /// A frame seen on the bus; frames come in time order.
  void add(const frames::TimedFrame& frame);
  /// Closes the windows that end at or before `now` (a quiet bus still has a load: 0).
  void advance(Nanos now);

  std::uint64_t frames() const noexcept { return frames_; }
  /// Bits on the wire over the last whole window, as a fraction of what the bit rate carries.
  double load() const noexcept { return load_; }
  /// Per periodic message seen in the last whole window: its name and the
  /// worst |period - nominal| there, in ms.
  const std::vector<std::pair<std::string, double>>& jitter_ms() const noexcept { return jitter_; }

 private:
  void close_window();

  std::shared_ptr<const frames::MessageSet> set_;
  std::uint32_t bit_rate_;
  Nanos window_;
  Nanos window_end_;
  std::uint64_t frames_ = 0;
  std::uint64_t bits_ = 0;  // in the open window
  double load_ = 0;
  struct PerMessage {
    Nanos nominal{0};
    Nanos last{-1};
    Nanos worst{-1};  // in the open window; -1: no period measured there
  };
  std::vector<PerMessage> messages_;  // parallel to the codec's messages
  std::vector<std::pair<std::string, double>> jitter_;
};

}  // namespace canhil::timing
