// canhil/vision_emu/runner.hpp — vision for several robots at its frame rate:
// keeps a short history of world snapshots (for the latency), makes each
// robot's frame and hands it to a sink (the session's, which writes it into
// the robot's VISION_INFO through emulator/LaptopLink; a test's).
#pragma once

#include <functional>
#include <random>

#include "canhil/base/ring.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/vision.hpp"

namespace canhil::vision_emu {

/// A snapshot of the physics world as vision sees it.
Scene snapshot(const physics::World& world);
/// The same into `into`, reusing its storage.
void snapshot(const physics::World& world, Scene& into);

class VisionRunner {
 public:
  using Sink = std::function<void(std::size_t robot, const VisionFrame& frame, double world_time_s)>;
  /// One Vision per robot (each may have its own parameters).
  VisionRunner(std::vector<Vision> per_robot, Sink sink);
  /// Call after every physics step: records the world and, when a robot's
  /// next frame is due, produces it from the snapshot `latency` ago.
  void on_step(const physics::World& world);
  std::uint64_t frames() const noexcept { return frames_; }

 private:
  std::vector<Vision> vision_;
  Sink sink_;
  base::Ring<Scene> history_;
  std::vector<Scene> spare_;  // scenes dropped from the history, their storage reused
  std::vector<double> next_frame_s_;
  std::vector<NoiseEngine> rng_;
  std::vector<VisionFrame> frame_;  // reused per robot
  std::uint64_t frames_ = 0;
};

}  // namespace canhil::vision_emu
