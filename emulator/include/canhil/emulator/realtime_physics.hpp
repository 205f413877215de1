// canhil/emulator/realtime_physics.hpp — the physics of a real-time run on a
// thread of its own.
//
// Step k happens at start + k * step_s on the wall clock (CLOCK_REALTIME,
// absolute sleeps, as the node loop). Before each step every robot's
// SharedRobotIo hands over the nodes' commands, after it the sensor values
// are published and the after-step hook runs (vision, goals, battery
// faults), all on this thread: the node thread never waits for a step, so
// physics and vision load does not move the frames on the bus. Falling
// behind is counted (late steps, worst lateness) and past `max_behind` the
// missed steps are skipped rather than run as a burst.
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "canhil/emulator/realtime.hpp"
#include "canhil/emulator/shared_robot_io.hpp"

namespace canhil::emulator {

class RealtimePhysics {
 public:
  /// What the other threads may look at while the physics runs.
  struct View {
    Eigen::Vector3d ball = Eigen::Vector3d::Zero();
    std::vector<kinematics::Pose> robots;
  };

  /// `world` and the `io` of each robot must outlive this; nothing runs before start().
  RealtimePhysics(physics::World& world, std::vector<SharedRobotIo*> io,
                  Nanos max_behind = std::chrono::milliseconds(100));
  ~RealtimePhysics();
  RealtimePhysics(const RealtimePhysics&) = delete;
  RealtimePhysics& operator=(const RealtimePhysics&) = delete;

  /// On the physics thread after every step, with the step's time.
  void on_step(std::function<void(Nanos)> f) { after_step_ = std::move(f); }
  /// Starts stepping; the first step is at `start` + one step.
  void start(Nanos start);
  /// Stops and joins the thread; the world is the caller's again.
  void stop();

  RealtimeStats stats() const;
  View view() const;

 private:
  void loop(Nanos start);

  physics::World& world_;
  std::vector<SharedRobotIo*> io_;
  Nanos max_behind_;
  Nanos step_;
  std::function<void(Nanos)> after_step_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mutex_;  // guards stats_ and view_
  RealtimeStats stats_;
  View view_;
};

}  // namespace canhil::emulator
