#include "canhil/emulator/realtime.hpp"

#include <algorithm>

namespace canhil::emulator {
namespace {

// Frames one node handles per pass of the loop: enough for any burst of the
// message set (a few dozen frames an EC), small enough that a socket flooded
// with other traffic costs a pass well under a millisecond.
constexpr std::size_t kPollBudget = 64;

}  // namespace

Realtime::Realtime(const can_nodes::Clock& clock, physics::World* world, Wait wait, Nanos max_behind)
    : clock_(clock), world_(world), wait_(std::move(wait)), max_behind_(max_behind) {
  if (world_ != nullptr) {
    step_ = std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(world_->params().simulation.step_s));
  }
}

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

void Realtime::run_until(Nanos end, const std::atomic<bool>& stop) {
  if (world_ != nullptr && next_step_ == kNever) next_step_ = clock_.now() + step_;
  while (!stop.load(std::memory_order_relaxed)) {
    const Nanos deadline =
        std::min({end, world_ != nullptr ? next_step_ : kNever, participants_.next_wakeup()});
    wait_(deadline);
    ++stats_.wakeups;
    // Timers first: a frame due goes out before the sockets are read (each
    // read is a system call, and a flooded socket has many). Bounded reads:
    // under a flood the loop comes straight back (the socket stays readable).
    participants_.tick_due(clock_, kPollBudget);
    const Nanos now = clock_.now();
    participants_.deliver_some(kPollBudget);
    if (world_ != nullptr && now >= next_step_) {
      book_step(stats_, now, next_step_, step_, max_behind_);
      world_->step();
      ++stats_.physics_steps;
      next_step_ += step_;
      if (after_step_) after_step_(now);
    }
    participants_.tick_due(clock_, kPollBudget);
    if (clock_.now() >= end) break;
  }
}

}  // namespace canhil::emulator
