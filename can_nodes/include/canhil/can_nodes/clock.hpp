// canhil/can_nodes/clock.hpp — the one injected clock.
//
// Nothing in canhil reads the wall clock except `main`, which builds a
// WallClock and hands it down. Tests and virtual-time runs use SimulatedClock
// and never sleep.
#pragma once

#include "canhil/frames/frame.hpp"

namespace canhil::can_nodes {

class Clock {
 public:
  virtual ~Clock() = default;
  /// Current time in nanoseconds since the clock's epoch. Thread-safe.
  virtual Nanos now() const noexcept = 0;
};

/// CLOCK_REALTIME, the clock SocketCAN stamps received frames with (so that
/// a frame's time and now() compare directly, and traces carry Unix time).
class WallClock final : public Clock {
 public:
  Nanos now() const noexcept override;
  /// Sleeps until the absolute time `t` on this clock (clock_nanosleep,
  /// TIMER_ABSTIME), or at most `at_most` (so a loop notices a stop request).
  static void sleep_until(Nanos t, Nanos at_most = std::chrono::milliseconds(100)) noexcept;
};

/// A clock that moves only when told. Not thread-safe: one owner advances it.
class SimulatedClock final : public Clock {
 public:
  explicit SimulatedClock(Nanos start = Nanos{0}) : now_(start) {}
  Nanos now() const noexcept override { return now_; }
  /// Moves time forward by `dt` (>= 0; a negative step is a broken invariant and aborts).
  void advance(Nanos dt);
  /// Sets the time to `t` (>= now(); time never runs backwards).
  void set(Nanos t);

 private:
  Nanos now_;
};

}  // namespace canhil::can_nodes
