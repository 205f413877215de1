// canhil/vision_emu/vision.hpp — emulated omnidirectional vision.
//
// From a snapshot of the world, what one robot's vision process would report:
// obstacle points (radial sensors against obstacle cylinders, nearest hit per
// sensor), line points (radial sensors in interleaved passes plus circular
// sensors, against the field's markings), and the ball (at its ground
// distance; a ball in the air projected to the ground, d = h d' / (h - h')),
// with occlusion: whatever lies beyond an obstacle in its shadow is not seen.
// Optional Gaussian noise, a detection probability and a latency. Robot frame,
// metres: x right, y forward. Pure: no RTDB, no clock (VisionRunner adds them).
#pragma once

#include <Eigen/Core>
#include <random>
#include <vector>

#include "canhil/kinematics/omni.hpp"
#include "canhil/physics/field.hpp"
#include "canhil/vision_emu/noise_engine.hpp"

namespace canhil::vision_emu {

struct VisionParams {
  double frame_rate_hz = 30.0;
  int obstacle_sensors = 240;  ///< radial, evenly spaced (1.5 deg)
  double obstacle_range_m = 6.0;
  int line_sensors = 30;  ///< radial sensors per pass
  int line_passes = 3;    ///< each pass rotated by 1/passes of the spacing
  std::vector<double> circle_radii_m = {0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0};  ///< circular sensors
  double line_range_m = 5.0;
  int max_line_points = 300;  ///< VisionInfo's MAX_POINTS
  int max_obstacle_points = 300;
  double camera_height_m = 0.73;  ///< h: body 0.165 m + cone 0.565 m
  double ball_see_limit_m = 5.0;  ///< s: the farthest ground distance a ball is seen at
  // Imperfections (off by default: exact geometry).
  double point_noise_m = 0.0;  ///< Gaussian sigma on line and obstacle points
  double ball_noise_m = 0.0;   ///< Gaussian sigma on the ball
  double detection_probability = 1.0;
  double latency_s = 0.0;  ///< data describes the world this long ago
  unsigned seed = 1;

  friend bool operator==(const VisionParams&, const VisionParams&) = default;
};

/// What vision needs of the world at one instant.
struct Scene {
  double time_s = 0;
  std::vector<kinematics::Pose> robots;
  double robot_radius_m = 0.25;  ///< robots as obstacles: their bounding radius
  struct Obstacle {
    Eigen::Vector2d centre;
    double radius_m;
  };
  std::vector<Obstacle> obstacles;
  Eigen::Vector3d ball{0, 0, 0.11};
  double ball_radius_m = 0.11;
};

/// One robot's frame. Points in the robot frame.
struct VisionFrame {
  std::vector<Eigen::Vector2d> obstacles;
  std::vector<Eigen::Vector2d> lines;
  std::vector<Eigen::Vector2d> balls;
  int line_rays = 0;  ///< radial line sensors evaluated (for reports)
};

class Vision {
 public:
  Vision(const VisionParams& params, physics::FieldMarkings markings);
  const VisionParams& params() const noexcept { return params_; }
  const physics::FieldMarkings& markings() const noexcept { return markings_; }

  /// What robot `robot` sees in `scene`. `rng` drives noise and detection.
  /// Thread-safe (scratch space is per thread).
  VisionFrame see(const Scene& scene, std::size_t robot, NoiseEngine& rng) const;
  /// The same into `out` (cleared first), reusing its storage: no allocation
  /// once the vectors have grown.
  void see(const Scene& scene, std::size_t robot, NoiseEngine& rng, VisionFrame& out) const;

  /// World point to robot frame, and back.
  static Eigen::Vector2d to_robot(const kinematics::Pose& pose, const Eigen::Vector2d& world);
  static Eigen::Vector2d to_world(const kinematics::Pose& pose, const Eigen::Vector2d& local);

 private:
  VisionParams params_;
  physics::FieldMarkings markings_;
  std::vector<double> ray_cos_;  // obstacle sensors
  std::vector<double> ray_sin_;
  std::vector<Eigen::Vector2d> line_dir_;   // line sensors, pass after pass
  std::vector<std::size_t> line_by_angle_;  // line sensors by angle: [j] points at 2 pi j / count
};

}  // namespace canhil::vision_emu
