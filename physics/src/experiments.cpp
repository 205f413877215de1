#include "canhil/physics/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "canhil/base/setup_error.hpp"
#include "canhil/kinematics/omni.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::physics {
namespace {

constexpr double kPi = std::numbers::pi;

std::string fmt(double v, int decimals = 2) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(decimals);
  os << v;
  return os.str();
}

Figure within(const std::string& name, double value, double target, double tolerance, int decimals = 2) {
  return Figure{name, value, fmt(target, decimals) + " +- " + fmt(tolerance, decimals),
                std::fabs(value - target) <= tolerance};
}

WorldParams empty_world(const WorldParams& base) {
  WorldParams p = base;
  p.robots.clear();
  p.obstacles.clear();
  return p;
}

// --- ball-drop -----------------------------------------------------------------

ExperimentResult ball_drop(const WorldParams& base, const ExperimentOptions& o) {
  const double height = o.height_m.value_or(1.0);
  WorldParams p = empty_world(base);
  const double r = p.ball.radius_m;
  p.ball_start = {0, 0, height + r};
  World w(p);
  ExperimentResult res;
  res.name = "ball-drop";
  res.description = "ball dropped from " + fmt(height) + " m (its bottom) onto the carpet";
  res.columns = {"bounce", "time_s", "impact_speed_mps", "rebound_speed_mps", "apex_height_m"};
  Series height_series{"height of the ball's bottom (m)", {}, {}};
  const double duration = o.duration_s > 0 ? o.duration_s : 5.0;
  // Record, then find the impacts (vertical velocity turning from down to up)
  // and each following flight's apex. A bounce is a rebound that lifts the
  // ball at least kMinApex: smaller hops are contact noise, not visible bounces.
  constexpr double kMinApex = 0.002;
  struct Impact {
    double time, in_speed, out_speed, apex;
  };
  std::vector<Impact> impacts;
  double last_vz = 0;
  while (w.time_s() < duration) {
    w.step();
    const double z = w.ball_position().z() - r;
    const double vz = w.ball_velocity().z();
    height_series.x.push_back(w.time_s());
    height_series.y.push_back(z);
    if (last_vz < -0.01 && vz >= -0.01) impacts.push_back({w.time_s(), -last_vz, std::max(vz, 0.0), 0});
    if (!impacts.empty()) impacts.back().apex = std::max(impacts.back().apex, z);
    last_vz = vz;
  }
  int bounces = 0;
  double rest_time = -1;
  for (const Impact& i : impacts) {
    if (i.apex >= kMinApex) {
      ++bounces;
      res.rows.push_back({static_cast<double>(bounces), i.time, i.in_speed, i.out_speed, i.apex});
    } else {
      rest_time = i.time;  // the first impact with no visible rebound: at rest from here
      break;
    }
  }
  res.figures.push_back(Figure{"bounces", static_cast<double>(bounces), "6", bounces == 6});
  res.figures.push_back(within("rest_time_s", rest_time, 2.81, 0.1));
  res.plots.push_back(Plot{"Ball drop from " + fmt(height) + " m", "time (s)", "height (m)", {height_series}});
  return res;
}

// --- ball-roll -------------------------------------------------------------------

ExperimentResult ball_roll(const WorldParams& base, const ExperimentOptions& o) {
  std::vector<double> speeds = {0.5, 1.0, 2.0, 3.0, 5.0};
  if (o.speed_mps) speeds = {*o.speed_mps};
  ExperimentResult res;
  res.name = "ball-roll";
  res.description = "ball rolling on the carpet from an initial speed until it stops";
  res.columns = {"speed_mps", "distance_m", "time_to_stop_s", "deceleration_mps2"};
  Plot plot{"Rolling ball", "time (s)", "speed (m/s)", {}};
  WorldParams p = empty_world(base);
  p.field.boundary = false;
  p.field.length_m = 200;  // room to roll out at any speed
  double expected_decel = p.ball.rolling_resistance * p.simulation.gravity_mps2;
  double worst = 0;
  for (double v : speeds) {
    World w(p);
    const double r = p.ball.radius_m;
    w.place_ball({-p.field.length_m / 2 - 0.5 + 0.2, 0, r}, {v, 0, 0}, {0, v / r, 0});
    const Eigen::Vector3d start = w.ball_position();
    Series s{fmt(v, 1) + " m/s", {}, {}};
    double stop_time = -1;
    const double duration = o.duration_s > 0 ? o.duration_s : 60.0;
    while (w.time_s() < duration) {
      w.step();
      const double speed = w.ball_velocity().head<2>().norm();
      s.x.push_back(w.time_s());
      s.y.push_back(speed);
      if (speed < 1e-3) {
        stop_time = w.time_s();
        break;
      }
    }
    const double distance = (w.ball_position() - start).head<2>().norm();
    const double decel = stop_time > 0 ? v / stop_time : 0;
    worst = std::max(worst, std::fabs(decel - expected_decel) / expected_decel);
    res.rows.push_back({v, distance, stop_time, decel});
    plot.series.push_back(std::move(s));
  }
  res.figures.push_back(
      Figure{"deceleration_error_pct", 100 * worst, "<= 10 (vs rolling_resistance * g)", worst <= 0.10});
  res.plots.push_back(std::move(plot));
  return res;
}

// --- kick ------------------------------------------------------------------------

struct KickRun {
  bool fired = false;
  double formula_speed = 0;
  double launch_speed = 0;
  double landing_distance = -1;
  Series height;
};

KickRun one_kick(const WorldParams& base, bool low, int power) {
  WorldParams p = empty_world(base);
  p.field.boundary = false;
  p.robots = {Placement{-6.0, 0, -90.0}};  // front (+y of the robot) along world +x
  World w(p);
  Robot& robot = w.robot(0);
  const RobotParams& rp = p.robot;
  const double hold = rp.body_radius_m - rp.mouth_depth_m + p.ball.radius_m;
  w.place_ball({-6.0 + hold, 0, p.ball.radius_m});
  robot.brake();
  robot.set_grabber(low ? 100 : 0);
  for (int i = 0; i < 50; ++i) w.step();  // settle; the grabber holds the ball
  KickRun run;
  const Eigen::Vector3d launch_pos = w.ball_position();
  const KickResult k = robot.kick(low, power);
  run.fired = k.fired();
  run.formula_speed = k.speed_mps;
  if (!run.fired) return run;
  // Launch speed: one step (10 ms) after the kick, when the ball has left the
  // mouth; a grabber still pulling, or the robot in the way, would show here.
  w.step();
  run.launch_speed = w.ball_velocity().norm();
  const double g = p.simulation.gravity_mps2;
  const double r = p.ball.radius_m;
  run.height.name = std::string(low ? "low" : "high") + " p=" + std::to_string(power);
  Eigen::Vector3d prev_pos = w.ball_position();
  Eigen::Vector3d prev_vel = w.ball_velocity();
  while (w.time_s() < 10) {
    w.step();
    const Eigen::Vector3d b = w.ball_position();
    const Eigen::Vector3d v = w.ball_velocity();
    run.height.x.push_back((b - launch_pos).head<2>().norm());
    run.height.y.push_back(b.z() - r);
    if (!low && prev_vel.z() < 0 && (v.z() >= 0 || w.ball_on_ground())) {
      // Landed during this step: solve the last airborne sample's parabola for z = r.
      const double z0 = prev_pos.z() - r;
      const double vz = prev_vel.z();
      const double t = (vz + std::sqrt(vz * vz + 2 * g * z0)) / g;
      const Eigen::Vector3d at = prev_pos + prev_vel * t;
      run.landing_distance = (at - launch_pos).head<2>().norm();
      break;
    }
    if (low && w.time_s() > 2.5) break;
    prev_pos = b;
    prev_vel = v;
  }
  return run;
}

ExperimentResult kick(const WorldParams& base, const ExperimentOptions& o) {
  ExperimentResult res;
  res.name = "kick";
  res.description = "kicks from a standing robot, ball held in the mouth (grabber on for low kicks)";
  res.columns = {"low", "power", "formula_speed_mps", "launch_speed_mps", "first_landing_m"};
  std::vector<std::pair<bool, int>> runs;
  const int pm = base.robot.kicker.max_power;
  if (o.low || o.power) {
    runs = {{o.low.value_or(false), o.power.value_or(pm)}};
  } else {
    for (bool low : {false, true}) {
      for (int p : {pm / 5, 2 * pm / 5, 3 * pm / 5, 4 * pm / 5, pm}) runs.emplace_back(low, p);
    }
  }
  Plot plot{"Kicks: ball height over distance", "distance (m)", "height (m)", {}};
  double worst_lob = 0;
  const KickerParams& kp = base.robot.kicker;
  const double theta = kp.lob_angle_deg * kPi / 180.0;
  for (const auto& [low, power] : runs) {
    KickRun r = one_kick(base, low, power);
    if (!low && r.fired) {
      // The flight is ballistic: range = v^2 sin(2 theta) / g from the launch speed.
      const double expected = r.formula_speed * r.formula_speed * std::sin(2 * theta) / base.simulation.gravity_mps2;
      worst_lob = std::max(worst_lob, std::fabs(r.landing_distance - expected) / expected);
    }
    res.rows.push_back(
        {low ? 1.0 : 0.0, static_cast<double>(power), r.formula_speed, r.launch_speed, r.landing_distance});
    if (!r.fired) {
      res.figures.push_back(Figure{"fired", 0, "the kicker fires with the ball held", false});
      continue;
    }
    if (power == pm && !low) {
      res.figures.push_back(within("high_full_power_landing_m", r.landing_distance, base.robot.kicker.max_lob_range_m,
                                   0.05 * base.robot.kicker.max_lob_range_m));
    }
    if (power == pm && low) {
      res.figures.push_back(
          within("low_full_power_launch_mps", r.launch_speed, r.formula_speed, 0.05 * r.formula_speed));
    }
    plot.series.push_back(std::move(r.height));
  }
  if (worst_lob > 0) {
    res.figures.push_back(
        Figure{"worst_lob_range_error_pct", 100 * worst_lob, "<= 5 (flight untouched by damping)", worst_lob <= 0.05});
  }
  res.plots.push_back(std::move(plot));
  return res;
}

// --- drive -------------------------------------------------------------------------

ExperimentResult drive(const WorldParams& base, const ExperimentOptions& o) {
  std::vector<kinematics::Twist> commands = {{1.0, 0, 0}, {0, 1.0, 0}, {0, 0, 2.0}};
  if (o.vx_mps || o.vy_mps || o.va_radps)
    commands = {{o.vx_mps.value_or(0), o.vy_mps.value_or(0), o.va_radps.value_or(0)}};
  ExperimentResult res;
  res.name = "drive";
  res.description = "wheel speeds from inverse kinematics, no correction factor; steady state over the last second";
  res.columns = {"cmd_vx", "cmd_vy", "cmd_va", "got_vx", "got_vy", "got_va", "error_pct"};
  Plot plot{"Drive: speed along the command", "time (s)", "achieved / commanded", {}};
  const double duration = o.duration_s > 0 ? o.duration_s : 3.0;
  double worst = 0;
  for (const kinematics::Twist& cmd : commands) {
    WorldParams p = empty_world(base);
    p.field.boundary = false;
    p.robots = {Placement{0, 0, 0}};
    p.ball_start = {0, 5, p.ball.radius_m};
    World w(p);
    Robot& robot = w.robot(0);
    const kinematics::OmniKinematics k(p.robot.geometry);
    const kinematics::WheelSpeeds ws = k.inverse(cmd);
    Series s{"vx " + fmt(cmd.vx_mps, 1) + " vy " + fmt(cmd.vy_mps, 1) + " va " + fmt(cmd.va_radps, 1), {}, {}};
    kinematics::Twist sum{};
    int samples = 0;
    const double norm = std::hypot(cmd.vx_mps, cmd.vy_mps) + std::fabs(cmd.va_radps);
    while (w.time_s() < duration) {
      for (int n = 0; n < 3; ++n) robot.set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
      w.step();
      const kinematics::Twist t = robot.twist();
      const double along = (t.vx_mps * cmd.vx_mps + t.vy_mps * cmd.vy_mps + t.va_radps * cmd.va_radps) /
                           (cmd.vx_mps * cmd.vx_mps + cmd.vy_mps * cmd.vy_mps + cmd.va_radps * cmd.va_radps);
      s.x.push_back(w.time_s());
      s.y.push_back(along);
      if (w.time_s() > duration - 1.0) {
        sum.vx_mps += t.vx_mps;
        sum.vy_mps += t.vy_mps;
        sum.va_radps += t.va_radps;
        ++samples;
      }
    }
    const kinematics::Twist got{sum.vx_mps / samples, sum.vy_mps / samples, sum.va_radps / samples};
    const double err = (std::fabs(got.vx_mps - cmd.vx_mps) + std::fabs(got.vy_mps - cmd.vy_mps) +
                        std::fabs(got.va_radps - cmd.va_radps)) /
                       norm;
    worst = std::max(worst, err);
    res.rows.push_back({cmd.vx_mps, cmd.vy_mps, cmd.va_radps, got.vx_mps, got.vy_mps, got.va_radps, 100 * err});
    plot.series.push_back(std::move(s));
  }
  res.figures.push_back(Figure{"worst_steady_state_error_pct", 100 * worst, "<= 3", worst <= 0.03});
  res.plots.push_back(std::move(plot));
  return res;
}

// --- tour -------------------------------------------------------------------------

ExperimentResult tour(const WorldParams& base, const ExperimentOptions& o) {
  WorldParams p = empty_world(base);
  p.robots = {Placement{-2, -2, 0}};
  p.ball_start = {5, 5, p.ball.radius_m};
  World w(p);
  Robot& robot = w.robot(0);
  const kinematics::OmniKinematics k(p.robot.geometry);
  const std::vector<std::array<double, 3>> waypoints = {{2, -2, 90}, {2, 2, 180}, {-2, 2, -90}, {-2, -2, 0}};
  // Odometry from the encoders only, as Pic_odom does it.
  kinematics::Pose odo = robot.pose();
  std::array<std::int64_t, 3> last_counts{};
  for (int n = 0; n < 3; ++n) last_counts[static_cast<std::size_t>(n)] = robot.encoder_count(n);
  const double dt = p.simulation.step_s;
  Series truth_path{"ground truth", {}, {}};
  Series odo_path{"odometry", {}, {}};
  double path_length = 0;
  kinematics::Pose last_truth = robot.pose();
  std::size_t target = 0;
  const double max_speed = 1.5;
  const double duration = o.duration_s > 0 ? o.duration_s : 60.0;
  ExperimentResult res;
  res.name = "tour";
  res.description = "four waypoints driven by a proportional controller on odometry from the wheel encoders";
  res.columns = {"waypoint", "time_s", "truth_x", "truth_y", "odo_x", "odo_y", "error_m"};
  while (target < waypoints.size() && w.time_s() < duration) {
    const auto& wp = waypoints[target];
    // World-frame error to robot frame, P control with a speed limit.
    const double ex = wp[0] - odo.x_m;
    const double ey = wp[1] - odo.y_m;
    const double eh = kinematics::wrap_pi(wp[2] * kPi / 180.0 - odo.heading_rad);
    const double c = std::cos(odo.heading_rad);
    const double s = std::sin(odo.heading_rad);
    kinematics::Twist cmd{2.0 * (c * ex + s * ey), 2.0 * (-s * ex + c * ey), 3.0 * eh};
    const double v = std::hypot(cmd.vx_mps, cmd.vy_mps);
    if (v > max_speed) {
      cmd.vx_mps *= max_speed / v;
      cmd.vy_mps *= max_speed / v;
    }
    cmd.va_radps = std::clamp(cmd.va_radps, -2.0, 2.0);
    const kinematics::WheelSpeeds ws = k.inverse(cmd);
    for (int n = 0; n < 3; ++n) robot.set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
    w.step();
    kinematics::WheelSpeeds measured{};
    for (int n = 0; n < 3; ++n) {
      const auto i = static_cast<std::size_t>(n);
      const std::int64_t now = robot.encoder_count(n);
      measured[i] = p.robot.encoder.wheel_angle_rad(static_cast<double>(now - last_counts[i])) / dt;
      last_counts[i] = now;
    }
    odo = kinematics::integrate(odo, k.forward(measured), dt);
    const kinematics::Pose truth = robot.pose();
    path_length += std::hypot(truth.x_m - last_truth.x_m, truth.y_m - last_truth.y_m);
    last_truth = truth;
    truth_path.x.push_back(truth.x_m);
    truth_path.y.push_back(truth.y_m);
    odo_path.x.push_back(odo.x_m);
    odo_path.y.push_back(odo.y_m);
    if (std::hypot(ex, ey) < 0.02 && std::fabs(eh) < 0.02) {
      res.rows.push_back({static_cast<double>(target + 1), w.time_s(), truth.x_m, truth.y_m, odo.x_m, odo.y_m,
                          std::hypot(truth.x_m - odo.x_m, truth.y_m - odo.y_m)});
      ++target;
    }
  }
  const kinematics::Pose truth = robot.pose();
  const double final_error = std::hypot(truth.x_m - odo.x_m, truth.y_m - odo.y_m);
  res.figures.push_back(Figure{"waypoints_reached", static_cast<double>(target), "4", target == waypoints.size()});
  res.figures.push_back(Figure{"path_length_m", path_length, "", true});
  res.figures.push_back(Figure{"final_odometry_error_pct", 100 * final_error / std::max(path_length, 1e-9), "<= 2",
                               final_error <= 0.02 * path_length});
  res.plots.push_back(Plot{"Tour: ground truth and odometry", "x (m)", "y (m)", {truth_path, odo_path}});
  return res;
}

}  // namespace

bool ExperimentResult::all_met() const {
  return std::all_of(figures.begin(), figures.end(), [](const Figure& f) { return f.met; });
}

std::vector<std::string> experiment_names() { return {"ball-drop", "ball-roll", "kick", "drive", "tour"}; }

ExperimentResult run_experiment(const std::string& name, const WorldParams& base, const ExperimentOptions& options) {
  if (name == "ball-drop") return ball_drop(base, options);
  if (name == "ball-roll") return ball_roll(base, options);
  if (name == "kick") return kick(base, options);
  if (name == "drive") return drive(base, options);
  if (name == "tour") return tour(base, options);
  std::string names;
  for (const auto& n : experiment_names()) names += (names.empty() ? "" : ", ") + n;
  throw SetupError("unknown experiment \"" + name + "\"; the experiments are " + names);
}

}  // namespace canhil::physics
