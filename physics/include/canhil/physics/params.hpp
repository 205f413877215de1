// canhil/physics/params.hpp — the immutable parameters of the physical world.
//
// Defaults are the figures of shared/design/reference-figures.md (CAMBADA
// robot, FIFA size 5 ball, the 18 m x 12 m field edition) or, where those give
// none, documented engineering values (docs/physics.md says which). Parameters
// never change while a world runs; everything that does is in WorldState.
// All units are in the names.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "canhil/kinematics/omni.hpp"

namespace canhil::physics {

struct SimulationParams {
  double step_s = 0.010;  ///< one world step (the nodes' and vision's clock ticks at this)
  int substeps = 1;       ///< ODE steps per world step (one of 10 ms by default; see docs/physics.md)
  double gravity_mps2 = 9.81;
  double cfm = 1e-5;  ///< global constraint force mixing
  double erp = 0.8;   ///< global error reduction
  /// ODE's exact (Dantzig LCP) solver instead of the iterative QuickStep; the
  /// islands here are small (one robot is about 27 constraint rows).
  bool exact_solver = true;
  /// With the exact solver, an island of more constraint rows than this (a
  /// scrum of three robots or more: one robot is about 27, the ball on the
  /// carpet 6, a contact 3) is stepped by QuickStep instead, whose cost grows
  /// with the rows rather than their cube; 0: every island exactly.
  int exact_solver_max_rows = 64;
  int solver_iterations = 10;  ///< QuickStep only (exact_solver false, or a large island)
  /// A movable obstacle still for this many steps sleeps (leaves the solver)
  /// until something touches it; 0 never sleeps.
  int sleep_after_steps = 20;
  unsigned long seed = 1;  ///< ODE's constraint-order shuffling; part of the saved state

  friend bool operator==(const SimulationParams&, const SimulationParams&) = default;
};

struct GoalParams {
  double width_m = 2.0;   ///< inside, between the posts
  double height_m = 1.0;  ///< inside, ground to bar
  double depth_m = 0.6;   ///< back of the net behind the goal line
  double post_thickness_m = 0.125;

  friend bool operator==(const GoalParams&, const GoalParams&) = default;
};

struct FieldParams {
  double length_m = 18.0;  ///< between the goal lines (x)
  double width_m = 12.0;   ///< between the touch lines (y)
  double line_width_m = 0.125;
  double centre_circle_radius_m = 2.0;
  double goal_area_depth_m = 0.75;
  double goal_area_width_m = 3.5;
  double penalty_area_depth_m = 2.25;
  double penalty_area_width_m = 6.5;
  double corner_arc_radius_m = 0.75;
  double penalty_mark_distance_m = 3.0;
  double margin_m = 1.0;  ///< carpet beyond the outer lines, up to the boundary
  bool boundary = true;   ///< walls around the carpet
  double boundary_height_m = 0.5;
  double ground_friction = 1.0;  ///< Coulomb friction of the carpet against bodies (not wheels, not ball)
  GoalParams goal;

  friend bool operator==(const FieldParams&, const FieldParams&) = default;
};

struct BallParams {
  double radius_m = 0.11;
  double mass_kg = 0.43;
  double restitution = 0.766;         ///< tuned to the drop test (6 bounces, rest at 2.81 s from 1 m)
  double bounce_min_speed_mps = 1.0;  ///< below this impact speed the ball does not bounce
  double friction = 0.8;              ///< ball against carpet and bodies
  double rolling_resistance = 0.035;  ///< deceleration / g while rolling on the carpet; 0 in flight
  double spin_damping = 0.5;          ///< 1/s, damps spin about the vertical while on the carpet

  friend bool operator==(const BallParams&, const BallParams&) = default;
};

struct MotorParams {
  double terminal_resistance_ohm = 0.299;  ///< 150 W, 24 V DC motor
  double torque_constant_nm_per_a = 0.0302;
  double gear_efficiency = 0.8;
  double current_limit_a = 10.0;  ///< the motor driver's limit
  double rotor_inertia_kgm2 = 1.4e-5;
  double stall_speed_radps = 0.5;  ///< wheel slower than this under load counts as stalled

  friend bool operator==(const MotorParams&, const MotorParams&) = default;
};

struct KickerParams {
  double lob_angle_deg = 45.0;        ///< theta of the high (lob) kick
  double max_lob_range_m = 9.0;       ///< r_m: first landing of a full-power lob at full charge
  int max_power = 50;                 ///< p_m; commands are capped to it
  double full_voltage_v = 180.0;      ///< capacitor when charged
  double min_fire_voltage_v = 40.0;   ///< below this the kicker does not fire
  double energy_per_full_kick = 0.7;  ///< fraction of the stored energy a full-power kick uses
  double recharge_time_constant_s = 1.5;
  double grabber_release_s = 0.25;  ///< the grabber lets go this long when the kicker fires

  friend bool operator==(const KickerParams&, const KickerParams&) = default;
};

struct BarrierParams {
  double half_angle_deg = 25.0;  ///< ball bearing within +- this of the front
  double max_distance_m = 0.30;  ///< robot centre to ball centre, horizontal
  double max_height_m = 0.16;    ///< ball centre above the carpet

  friend bool operator==(const BarrierParams&, const BarrierParams&) = default;
};

struct GrabberParams {
  double range_m = 0.45;  ///< robot centre to ball centre where the wheel reaches
  double half_angle_deg = 35.0;
  double max_force_n = 6.0;  ///< pull at mode 100

  friend bool operator==(const GrabberParams&, const GrabberParams&) = default;
};

struct CompassParams {
  double north_offset_deg = 0.0;  ///< world yaw (CCW from +x) of magnetic north

  friend bool operator==(const CompassParams&, const CompassParams&) = default;
};

struct RailParams {
  double full_v = 0;
  double empty_v = 0;
  double capacity_ah = 0;
  double internal_resistance_ohm = 0;
  double base_current_a = 0;  ///< electronics always drawing

  friend bool operator==(const RailParams&, const RailParams&) = default;
};

struct BatteryParams {
  RailParams logic{12.6, 10.5, 5.0, 0.05, 2.0};
  RailParams power12{12.6, 10.5, 10.0, 0.05, 1.0};
  RailParams power24{25.2, 21.0, 10.0, 0.08, 0.3};  ///< feeds the three motors
  double initial_charge = 1.0;                      ///< state of charge at start, 0..1

  friend bool operator==(const BatteryParams&, const BatteryParams&) = default;
};

struct RobotParams {
  double body_radius_m = 0.25;
  double body_height_m = 0.145;
  double body_clearance_m = 0.02;  ///< carpet to the body's underside
  double mouth_width_m = 0.26;     ///< front cut-out that holds the ball
  double mouth_depth_m = 0.10;
  double cone_radius_m = 0.24;  ///< camera cone on top
  double cone_height_m = 0.565;
  double cone_top_radius_m = 0.04;
  double mass_kg = 28.0;  ///< without wheels
  double wheel_mass_kg = 0.4;
  double wheel_friction = 1.2;        ///< along the drive direction
  double wheel_cross_friction = 0.0;  ///< across it: the rollers turn freely
  kinematics::OmniGeometry geometry;
  kinematics::EncoderSpec encoder;
  MotorParams motor;
  KickerParams kicker;
  BarrierParams barrier;
  GrabberParams grabber;
  CompassParams compass;
  BatteryParams battery;

  friend bool operator==(const RobotParams&, const RobotParams&) = default;
};

struct ObstacleParams {
  double radius_m = 0.25;
  double height_m = 0.7;
  double mass_kg = 30.0;  ///< movable obstacles only
  double friction = 0.3;  ///< against the carpet (movable only): a robot can push it
  bool movable = false;

  friend bool operator==(const ObstacleParams&, const ObstacleParams&) = default;
};

/// Where things start.
struct Placement {
  double x_m = 0;
  double y_m = 0;
  double heading_deg = 0;  ///< robots: CCW from +x of the robot's +x axis (front is +y)

  friend bool operator==(const Placement&, const Placement&) = default;
};

struct ObstaclePlacement {
  Placement at;
  ObstacleParams params;

  friend bool operator==(const ObstaclePlacement&, const ObstaclePlacement&) = default;
};

struct BallStart {
  double x_m = 0;
  double y_m = 0;
  double z_m = 0.11;  ///< centre height; resting on the carpet by default

  friend bool operator==(const BallStart&, const BallStart&) = default;
};

struct WorldParams {
  SimulationParams simulation;
  FieldParams field;
  BallParams ball;
  RobotParams robot;  ///< the robot model, shared by every robot
  std::vector<Placement> robots;
  std::vector<ObstaclePlacement> obstacles;
  BallStart ball_start;

  friend bool operator==(const WorldParams&, const WorldParams&) = default;
};

}  // namespace canhil::physics
