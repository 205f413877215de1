// canhil/emulator/realtime.hpp — hardware in the loop: the same participants
// as Lockstep, paced by the wall clock.
//
// The loop never reads the wall clock itself: `main` passes the clock and a
// `wait(deadline)` that returns at the absolute deadline or earlier when a
// frame arrives (canhil uses a timerfd with TFD_TIMER_ABSTIME polled together
// with the sockets). Physics steps are locked to the clock: step k happens at
// start + k * step_s. When the loop falls behind it says so (late steps are
// counted, the worst lateness kept) and, past `max_behind`, skips ahead
// rather than running a burst of steps.
#pragma once

#include <atomic>
#include <functional>
#include <vector>

#include "canhil/emulator/lockstep.hpp"

namespace canhil::emulator {

struct RealtimeStats {
  std::uint64_t physics_steps = 0;
  std::uint64_t late_steps = 0;     ///< physics steps taken more than one step late
  std::uint64_t skipped_steps = 0;  ///< steps dropped to catch up after a stall
  Nanos worst_lateness{0};
  std::uint64_t wakeups = 0;
};

/// Books a physics step due at `due` and taken at `now` in `stats` (its
/// lateness; a late step; past `max_behind`, the missed steps skipped, `due`
/// moved past them rather than running them as a burst).
void book_step(RealtimeStats& stats, Nanos now, Nanos& due, Nanos step, Nanos max_behind) noexcept;

class Realtime {
 public:
  using Wait = std::function<void(Nanos deadline)>;
  /// `clock`, `world` (may be null) and `wait` must outlive the loop.
  Realtime(const can_nodes::Clock& clock, physics::World* world, Wait wait,
           Nanos max_behind = std::chrono::milliseconds(100));
  void add(Participant& p) { participants_.add(p); }
  void add(can_nodes::Node& node) { participants_.add(node); }
  /// Runs until the clock reads `end` or `stop` becomes true.
  void run_until(Nanos end, const std::atomic<bool>& stop);
  const RealtimeStats& stats() const noexcept { return stats_; }
  /// Called after every physics step.
  void on_physics_step(std::function<void(Nanos)> f) { after_step_ = std::move(f); }

 private:
  const can_nodes::Clock& clock_;
  physics::World* world_;
  Wait wait_;
  Nanos max_behind_;
  Nanos step_{0};
  Nanos next_step_ = kNever;
  Participants participants_;
  RealtimeStats stats_;
  std::function<void(Nanos)> after_step_;
};

}  // namespace canhil::emulator
