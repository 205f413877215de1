// canhil/emulator/realtime_physics.hpp — a session's physics on a thread of
// its own, on the wall clock.
//
// Step k happens at start + k * step on the wall clock (CLOCK_REALTIME,
// absolute sleeps, as the node loop). Each step is the session's
// (Session::step, without the bus changes, which the node thread applies):
// before_step (queued changes, the nodes' commands through SharedRobotIo), the
// world's step, after_step (sensor values published, battery faults, vision,
// goals, the snapshot), all on this thread: the node thread never waits for a step,
// so physics and vision load does not move the frames on the bus. Falling
// behind is counted (late steps, worst lateness) and past `max_behind` the
// missed steps are skipped rather than run as a burst.
#pragma once

#include <atomic>
#include <mutex>
#include <thread>

#include "canhil/base/periodic.hpp"
#include "canhil/base/pi_mutex.hpp"
#include "canhil/can_nodes/clock.hpp"
#include "canhil/emulator/session.hpp"

namespace canhil::emulator {

struct RealtimeStats {
  std::uint64_t physics_steps = 0;
  std::uint64_t late_steps = 0;     ///< physics steps taken more than one step late
  std::uint64_t skipped_steps = 0;  ///< steps dropped to catch up after a stall
  Nanos worst_lateness{0};
};

/// Books the step `steps` has due, taken at `now`, in `stats` (its lateness;
/// a late step; past `max_behind`, the missed steps skipped, `steps` moved
/// past them rather than running them as a burst).
void book_step(RealtimeStats& stats, Nanos now, Periodic& steps, Nanos max_behind) noexcept;

class RealtimePhysics {
 public:
  /// `session` (its nodes built with shared I/O) and `clock` (the run's, which
  /// the nodes' loop reads too) must outlive this; nothing runs before start().
  RealtimePhysics(Session& session, const can_nodes::WallClock& clock,
                  Nanos max_behind = std::chrono::milliseconds(100));
  ~RealtimePhysics();
  RealtimePhysics(const RealtimePhysics&) = delete;
  RealtimePhysics& operator=(const RealtimePhysics&) = delete;

  /// Starts stepping; the first step is at `start` + one step.
  void start(Nanos start);
  /// Stops and joins the thread; the world is the caller's again.
  void stop();
  RealtimeStats stats() const;

 private:
  void loop(Nanos start);

  Session& session_;
  const can_nodes::WallClock& clock_;
  Nanos max_behind_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable PiMutex mutex_;  // guards stats_ (read by the node thread, SCHED_FIFO)
  RealtimeStats stats_;
};

}  // namespace canhil::emulator
