#include "canhil/emulator/realtime_physics.hpp"

#include <algorithm>

namespace canhil::emulator {

RealtimePhysics::RealtimePhysics(physics::World& world, std::vector<SharedRobotIo*> io, Nanos max_behind)
    : world_(world),
      io_(std::move(io)),
      max_behind_(max_behind),
      step_(std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(world.params().simulation.step_s))) {
  view_.ball = world_.ball_position();
  for (std::size_t r = 0; r < world_.robot_count(); ++r) view_.robots.push_back(world_.robot(r).pose());
}

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

RealtimePhysics::View RealtimePhysics::view() const {
  const std::lock_guard lock(mutex_);
  return view_;
}

void RealtimePhysics::loop(Nanos start) {
  Nanos next = start + step_;
  RealtimeStats stats;
  View view = view_;
  while (!stop_.load(std::memory_order_relaxed)) {
    if (can_nodes::WallClock{}.now() < next) {
      can_nodes::WallClock::sleep_until(next);
      continue;
    }
    const Nanos now = can_nodes::WallClock{}.now();
    book_step(stats, now, next, step_, max_behind_);
    for (SharedRobotIo* io : io_) io->apply_commands();
    world_.step();
    ++stats.physics_steps;
    next += step_;
    for (SharedRobotIo* io : io_) io->publish();
    if (after_step_) after_step_(now);
    view.ball = world_.ball_position();
    for (std::size_t r = 0; r < view.robots.size(); ++r) view.robots[r] = world_.robot(r).pose();
    const std::lock_guard lock(mutex_);
    stats_ = stats;
    view_ = view;
  }
}

}  // namespace canhil::emulator
