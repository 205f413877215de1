// canhil/can_nodes/realtime.hpp — hardware in the loop: the same participants
// as VirtualTime, paced by the wall clock.
//
// The loop never reads the wall clock itself: its owner passes the clock and
// a `wait(deadline)` that returns at the absolute deadline or earlier when a
// frame arrives (emulator::WallWaiter: a timerfd with TFD_TIMER_ABSTIME
// polled together with the sockets). Due frames go out before sockets are
// read, and each participant reads a bounded number of frames per pass, so a
// flooded socket cannot hold up a deadline.
//
// Not thread-safe: one thread runs a loop; several loops may run on several
// threads over disjoint participants.
#pragma once

#include <atomic>
#include <functional>

#include "canhil/can_nodes/virtual_time.hpp"

namespace canhil::can_nodes {

class Realtime {
 public:
  using Wait = std::function<void(Nanos deadline)>;
  /// `clock` and `wait` must outlive the loop.
  Realtime(const Clock& clock, Wait wait) : clock_(clock), wait_(std::move(wait)) {}
  void add(Participant& p) { participants_.add(p); }
  void add(Node& node) { participants_.add(node); }
  /// Called once every pass of the loop, before the due frames (changes the
  /// owner queued for this thread, e.g. fault rules). Must be cheap.
  void on_pass(std::function<void()> f) { on_pass_ = std::move(f); }
  /// Runs until the clock reads `end` or `stop` becomes true.
  void run_until(Nanos end, const std::atomic<bool>& stop);
  std::uint64_t wakeups() const noexcept { return wakeups_; }

 private:
  const Clock& clock_;
  Wait wait_;
  Participants participants_;
  std::function<void()> on_pass_;
  std::uint64_t wakeups_ = 0;
};

}  // namespace canhil::can_nodes
