// canhil/emulator/step_timing.hpp — what a run's steps cost
// (SessionOptions::time_steps): the world's steps in CPU time with a
// least-squares line of one step's CPU time over the contact points it made,
// and the emulated vision that follows each step, so that `canhil bench
// --part match` can say what the physics itself costs per contact and what
// is left once the physics and the camera are paid for.
#pragma once

#include <cstdint>

#include "canhil/base/time.hpp"

namespace canhil::emulator {

struct PhysicsTiming {
  Nanos cpu{0};  ///< the steps' CPU time, all of them
  std::uint64_t steps = 0;
  // Sums for the line: x a step's contact points, y its CPU time in us.
  double sum_x = 0;
  double sum_y = 0;
  double sum_xy = 0;
  double sum_xx = 0;

  /// One step that made `contact_points` contact points in `cpu_time`.
  void add(std::uint64_t contact_points, Nanos cpu_time) noexcept {
    const auto x = static_cast<double>(contact_points);
    const double y = to_seconds(cpu_time) * 1e6;
    cpu += cpu_time;
    ++steps;
    sum_x += x;
    sum_y += y;
    sum_xy += x * y;
    sum_xx += x * x;
  }

  PhysicsTiming& operator+=(const PhysicsTiming& other) noexcept {
    cpu += other.cpu;
    steps += other.steps;
    sum_x += other.sum_x;
    sum_y += other.sum_y;
    sum_xy += other.sum_xy;
    sum_xx += other.sum_xx;
    return *this;
  }

  /// Contact points a step, on average.
  double contacts_per_step() const noexcept { return steps == 0 ? 0 : sum_x / static_cast<double>(steps); }

  /// The line's slope: CPU microseconds a step per contact point. 0 when
  /// every step made as many contact points (no line to fit).
  double us_per_contact() const noexcept {
    const auto n = static_cast<double>(steps);
    const double spread = n * sum_xx - sum_x * sum_x;
    return spread > 1e-9 * n * n ? (n * sum_xy - sum_x * sum_y) / spread : 0;
  }
};

struct StepTiming {
  PhysicsTiming physics;  ///< the world's steps
  /// The emulated vision after each step: the frames due seen, with their
  /// noise, and written to the RTDB (VISION_INFO), as a team's camera costs.
  Nanos vision{0};

  StepTiming& operator+=(const StepTiming& other) noexcept {
    physics += other.physics;
    vision += other.vision;
    return *this;
  }
};

}  // namespace canhil::emulator
