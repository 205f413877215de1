#include "canhil/emulator/realtime_physics.hpp"

#include <algorithm>

namespace canhil::emulator {

void book_step(RealtimeStats& stats, Nanos now, Nanos& due, Nanos step, Nanos max_behind) noexcept {
  const Nanos late = now - due;
  stats.worst_lateness = std::max(stats.worst_lateness, late);
  if (late > step) ++stats.late_steps;
  if (late > max_behind) {
    // Stalled (debugger, overloaded machine): drop the missed steps.
    const auto missed = late / step;
    stats.skipped_steps += static_cast<std::uint64_t>(missed);
    due += step * missed;
  }
}

RealtimePhysics::RealtimePhysics(Session& session, Nanos max_behind) : session_(session), max_behind_(max_behind) {}

RealtimePhysics::~RealtimePhysics() { stop(); }

void RealtimePhysics::start(Nanos start) {
  stop_ = false;
  thread_ = std::thread([this, start] { loop(start); });
}

void RealtimePhysics::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

RealtimeStats RealtimePhysics::stats() const {
  const std::lock_guard lock(mutex_);
  return stats_;
}

void RealtimePhysics::loop(Nanos start) {
  const Nanos step = session_.step_period();
  Nanos next = start + step;
  RealtimeStats stats;
  while (!stop_.load(std::memory_order_relaxed)) {
    if (can_nodes::WallClock{}.now() < next) {
      can_nodes::WallClock::sleep_until(next);
      continue;
    }
    const Nanos now = can_nodes::WallClock{}.now();
    book_step(stats, now, next, step, max_behind_);
    session_.step(now, false);  // the bus changes: on the nodes' thread (RealtimeDriver)
    ++stats.physics_steps;
    next += step;
    const std::lock_guard lock(mutex_);
    stats_ = stats;
  }
}

}  // namespace canhil::emulator
