#include "canhil/emulator/run_control.hpp"

#include <cmath>
#include <string>

#include "canhil/base/setup_error.hpp"

namespace canhil::emulator {

RunControl::RunControl(Nanos ec, double speed, bool paused) : ec_(ec), paused_(paused), speed_(0) {
  if (ec_ <= Nanos{0}) throw SetupError("a run's elementary cycle must be above 0");
  set_speed(speed);
}

void RunControl::pause() {
  const std::lock_guard lock(mutex_);
  paused_ = true;
  ++requests_;
  changed_.notify_all();
}

void RunControl::resume() {
  const std::lock_guard lock(mutex_);
  paused_ = false;
  steps_asked_ = 0;
  anchored_ = false;  // the pace starts again from where the run stands
  ++requests_;
  changed_.notify_all();
}

void RunControl::step(std::uint32_t count) {
  if (count < 1 || count > 10000) throw SetupError("step takes 1..10000 elementary cycles");
  const std::lock_guard lock(mutex_);
  if (!paused_) throw SetupError("the run is not paused; pause it first, then step");
  steps_asked_ += count;
  ++requests_;
  changed_.notify_all();
}

void RunControl::check_speed(double factor) {
  if (!(factor == 0 || (std::isfinite(factor) && factor >= kMinSpeed && factor <= kMaxSpeed))) {
    throw SetupError("speed takes 0 (as fast as possible) or " + std::to_string(kMinSpeed) + ".." +
                     std::to_string(kMaxSpeed) + " (virtual seconds per wall second)");
  }
}

void RunControl::set_speed(double factor) {
  check_speed(factor);
  const std::lock_guard lock(mutex_);
  speed_ = factor;
  anchored_ = false;
  ++requests_;
  changed_.notify_all();
}

bool RunControl::paused() const {
  const std::lock_guard lock(mutex_);
  return paused_;
}

double RunControl::speed() const {
  const std::lock_guard lock(mutex_);
  return speed_;
}

Nanos RunControl::boundary_at_or_after(Nanos t) const { return ((t + ec_ - Nanos{1}) / ec_) * ec_; }
Nanos RunControl::boundary_at_or_before(Nanos t) const { return (t / ec_) * ec_; }

RunControl::Plan RunControl::next(Nanos now, Nanos wall, Nanos end) {
  const std::lock_guard lock(mutex_);
  planned_at_ = requests_;
  // Off a boundary (a run that started off one): first back onto the grid.
  const Nanos grid = boundary_at_or_after(now);
  if (grid != now) return Plan{std::min(grid, end), Nanos{0}};
  if (paused_) {
    if (steps_asked_ == 0) return Plan{now, std::chrono::milliseconds(100)};
    --steps_asked_;
    return Plan{std::min(now + ec_, end), Nanos{0}};
  }
  if (speed_ == 0) return Plan{std::min(boundary_at_or_after(now + kChunk), end), Nanos{0}};
  if (!anchored_) {
    anchored_ = true;
    anchor_virtual_ = now;
    anchor_wall_ = wall;
  }
  const auto due = [&](Nanos wall_time) {
    return anchor_virtual_ +
           Nanos{static_cast<std::int64_t>(static_cast<double>((wall_time - anchor_wall_).count()) * speed_)};
  };
  Nanos target = due(wall);
  if (target - now > kMaxBehind) {  // the machine cannot keep this pace: carry on from here
    anchor_virtual_ = now;
    anchor_wall_ = wall;
    target = now;
  }
  const Nanos run_to = std::min(boundary_at_or_before(target), end);
  if (run_to > now) return Plan{run_to, Nanos{0}};
  // Ahead: wait until the next EC is due.
  const Nanos next_due =
      anchor_wall_ +
      Nanos{static_cast<std::int64_t>(static_cast<double>((now + ec_ - anchor_virtual_).count()) / speed_)};
  return Plan{now, std::max(next_due - wall, Nanos{0})};
}

void RunControl::wait(Nanos wall_wait) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, wall_wait, [&] { return requests_ != planned_at_; });
}

}  // namespace canhil::emulator
