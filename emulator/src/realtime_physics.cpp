#include "canhil/emulator/realtime_physics.hpp"

#include <algorithm>

namespace canhil::emulator {

void book_step(RealtimeStats& stats, Nanos now, Periodic& steps, Nanos max_behind) noexcept {
  const Nanos late = now - steps.next();
  stats.worst_lateness = std::max(stats.worst_lateness, late);
  if (late > steps.period()) ++stats.late_steps;
  if (late > max_behind) {
    // Stalled (debugger, overloaded machine): drop the missed steps.
    const auto missed = late / steps.period();
    stats.skipped_steps += static_cast<std::uint64_t>(missed);
    steps.skip(missed);
  }
}

RealtimePhysics::RealtimePhysics(Session& session, const can_nodes::WallClock& clock, Nanos max_behind)
    : session_(session), clock_(clock), max_behind_(max_behind) {}

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
  Periodic steps(session_.step_period(), start + session_.step_period());
  RealtimeStats stats;
  while (!stop_.load(std::memory_order_relaxed)) {
    const Nanos now = clock_.now();
    if (!steps.due(now)) {
      clock_.sleep_until(steps.next());
      continue;
    }
    book_step(stats, now, steps, max_behind_);
    session_.step(now, false);  // the bus changes: on the nodes' thread (RealtimeDriver)
    ++stats.physics_steps;
    steps.advance();
    const std::lock_guard lock(mutex_);
    stats_ = stats;
  }
}

}  // namespace canhil::emulator
