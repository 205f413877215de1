#include "canhil/vision_emu/vision.hpp"

#include "canhil/vision_emu/gaussian.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace canhil::vision_emu {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Circle {
  Eigen::Vector2d c;  // robot frame
  double r;
  double dist;        // centre distance
  double bearing;     // of the centre, by rough_atan2: for choosing which sensors test it, never for a point
  double half_width;  // angular half-width as seen from the camera
  double c2_r2;       // |c|^2 - r^2, the same for every ray
};

// Nearest t >= 0 where origin + t * dir hits the circle, or inf.
double ray_circle(const Eigen::Vector2d& dir, const Circle& c) {
  const double b = dir.dot(c.c);
  if (b < 0) return kInf;  // behind the camera: t = b - sqrt(disc) < 0
  const double disc = b * b - c.c2_r2;
  if (disc < 0) return kInf;
  const double t = b - std::sqrt(disc);
  return t >= 0 ? t : kInf;
}

// Does the segment from the origin to p pass through the circle (p beyond it)?
// `circles` are nearest edge first: the first whose near edge lies beyond p
// ends the search.
bool occluded(const Eigen::Vector2d& p, const std::vector<Circle>& circles) {
  const double len = p.norm();
  if (len < 1e-9) return false;
  const Eigen::Vector2d dir = p / len;
  for (const Circle& c : circles) {
    if (c.dist - c.r > len) break;  // this obstacle, and every one after it, is farther than the point
    const double t = ray_circle(dir, c);
    if (t < len - 1e-9) return true;
  }
  return false;
}

double wrap_angle(double a) { return std::remainder(a, 2 * kPi); }

// World points into a robot's frame (Vision::to_robot), the heading's cosine and sine taken once.
class RobotFrame {
 public:
  explicit RobotFrame(const kinematics::Pose& pose)
      : pose_(pose), c_(std::cos(pose.heading_rad)), s_(std::sin(pose.heading_rad)) {}
  Eigen::Vector2d local(const Eigen::Vector2d& w) const {
    const double dx = w.x() - pose_.x_m;
    const double dy = w.y() - pose_.y_m;
    return {c_ * dx + s_ * dy, -s_ * dx + c_ * dy};
  }

 private:
  kinematics::Pose pose_;
  double c_;
  double s_;
};

// atan2 within 2.1e-4 rad (measured over 10^7 random points), for choosing which
// sensors to test, with a sensor or a margin to spare (never for a point).
double rough_atan2(double y, double x) {
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  const double hi = std::max(ax, ay);
  if (hi == 0) return 0;
  const double a = std::min(ax, ay) / hi;
  const double s = a * a;
  double r = ((-0.0464964749 * s + 0.15931422) * s - 0.327622764) * s * a + a;
  if (ay > ax) r = kPi / 2 - r;
  if (x < 0) r = kPi - r;
  return y < 0 ? -r : r;
}

bool on_arc(const physics::LineArc& a, double angle) {
  double rel = std::fmod(angle - a.start_rad, 2 * kPi);
  if (rel < 0) rel += 2 * kPi;
  return rel <= (a.end_rad - a.start_rad) + 1e-12;
}

}  // namespace

Vision::Vision(const VisionParams& params, physics::FieldMarkings markings)
    : params_(params), markings_(std::move(markings)) {
  const int n = std::max(1, params_.obstacle_sensors);
  for (int i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    ray_cos_.push_back(std::cos(a));
    ray_sin_.push_back(std::sin(a));
  }
  const int sensors = std::max(1, params_.line_sensors);
  const int passes = std::max(1, params_.line_passes);
  for (int pass = 0; pass < passes; ++pass) {
    for (int k = 0; k < sensors; ++k) {
      // Pass p fills the gaps the earlier passes left: offset by p/passes of the spacing.
      const double angle = 2 * kPi * (k + static_cast<double>(pass) / passes) / sensors;
      line_dir_.emplace_back(std::cos(angle), std::sin(angle));
    }
  }
  line_by_angle_.resize(line_dir_.size());
  const auto n_sensors = static_cast<std::size_t>(sensors);
  const auto n_passes = static_cast<std::size_t>(passes);
  for (std::size_t pass = 0; pass < n_passes; ++pass) {
    for (std::size_t k = 0; k < n_sensors; ++k) line_by_angle_[k * n_passes + pass] = pass * n_sensors + k;
  }
}

Eigen::Vector2d Vision::to_robot(const kinematics::Pose& pose, const Eigen::Vector2d& w) {
  return RobotFrame(pose).local(w);
}

Eigen::Vector2d Vision::to_world(const kinematics::Pose& pose, const Eigen::Vector2d& l) {
  const double c = std::cos(pose.heading_rad);
  const double s = std::sin(pose.heading_rad);
  return {pose.x_m + c * l.x() - s * l.y(), pose.y_m + s * l.x() + c * l.y()};
}

VisionFrame Vision::see(const Scene& scene, std::size_t robot, NoiseEngine& rng) const {
  VisionFrame out;
  see(scene, robot, rng, out);
  return out;
}

void Vision::see(const Scene& scene, std::size_t robot, NoiseEngine& rng, VisionFrame& out) const {
  out.obstacles.clear();
  out.lines.clear();
  out.balls.clear();
  out.line_rays = 0;
  const kinematics::Pose& me = scene.robots.at(robot);
  const RobotFrame frame(me);  // the heading's cosine and sine once a frame
  const auto local = [&frame](const Eigen::Vector2d& w) { return frame.local(w); };
  // Single-precision draws (about one engine call each): ample for centimetre noise.
  const Gaussian point_noise(static_cast<float>(params_.point_noise_m));
  std::uniform_real_distribution<float> chance(0.0f, 1.0f);
  const bool noisy = params_.point_noise_m > 0;
  const auto detection = static_cast<float>(params_.detection_probability);

  // Scratch space, per thread, reused frame after frame.
  thread_local std::vector<Circle> circles;
  circles.clear();
  auto add_circle = [&](const Eigen::Vector2d& world, double r) {
    const Eigen::Vector2d c = local(world);
    const double d = c.norm();
    if (d <= r + 1e-9 || d - r > params_.obstacle_range_m + params_.line_range_m) return;
    circles.push_back({c, r, d, rough_atan2(c.y(), c.x()), std::asin(std::min(1.0, r / d)), c.squaredNorm() - r * r});
  };
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    if (i != robot) add_circle({scene.robots[i].x_m, scene.robots[i].y_m}, scene.robot_radius_m);
  }
  for (const auto& o : scene.obstacles) add_circle(o.centre, o.radius_m);
  // Nearest edge first, for occluded(); every other use takes a minimum over them.
  std::sort(circles.begin(), circles.end(),
            [](const Circle& x, const Circle& y) { return x.dist - x.r < y.dist - y.r; });

  // --- obstacle points: nearest hit per radial sensor, only where a circle lies.
  const int n_obs = static_cast<int>(ray_cos_.size());
  thread_local std::vector<double> nearest;
  nearest.assign(static_cast<std::size_t>(n_obs), kInf);
  // The sensors some circle's span reached, a bit each: most of the 240 see
  // nothing, and the points are then taken from these alone, in sensor order.
  thread_local std::vector<std::uint64_t> reached;
  reached.assign((nearest.size() + 63) / 64, 0);
  const double step = 2 * kPi / n_obs;
  for (const Circle& c : circles) {
    if (c.dist - c.r > params_.obstacle_range_m) continue;
    // The sensors within its angle, and any within the bearing's error beyond it
    // (those miss it: ray_circle decides).
    constexpr double kBearingError = 5e-4;  // rough_atan2 errs by at most 2.1e-4
    const int first = static_cast<int>(std::ceil((c.bearing - c.half_width - kBearingError) / step));
    const int last = static_cast<int>(std::floor((c.bearing + c.half_width + kBearingError) / step));
    auto i = static_cast<std::size_t>(((first % n_obs) + n_obs) % n_obs);  // one division, then wrap by hand
    for (int k = first; k <= last; ++k, i = i + 1 == nearest.size() ? 0 : i + 1) {
      const double t = ray_circle({ray_cos_[i], ray_sin_[i]}, c);
      if (t < nearest[i]) {
        nearest[i] = t;
        reached[i / 64] |= std::uint64_t{1} << (i % 64);
      }
    }
  }
  bool obstacle_room = true;
  for (std::size_t w = 0; w < reached.size() && obstacle_room; ++w) {
    for (std::uint64_t bits = reached[w]; bits != 0; bits &= bits - 1) {
      const std::size_t i = w * 64 + static_cast<std::size_t>(std::countr_zero(bits));
      if (nearest[i] > params_.obstacle_range_m) continue;
      if (static_cast<int>(out.obstacles.size()) >= params_.max_obstacle_points) {
        obstacle_room = false;
        break;
      }
      if (detection < 1 && chance(rng) > detection) continue;
      Eigen::Vector2d p(ray_cos_[i] * nearest[i], ray_sin_[i] * nearest[i]);
      if (noisy) p += Eigen::Vector2d(point_noise(rng), point_noise(rng));
      out.obstacles.push_back(p);
    }
  }

  // --- line points: marking geometry in the robot frame, only what lies
  // within reach: no sensor sees a point farther than line_range_m (a ray
  // stops there, a ring's radius is at most that), so a marking wholly beyond
  // it gives no point and is left out of the per-ray work.
  const double reach = params_.line_range_m + 1e-9;
  struct Seg {
    Eigen::Vector2d a, b;
    Eigen::Vector2d e;  // b - a
    double a_cross_e;   // a x e: the numerator of every ray's t
  };
  thread_local std::vector<Seg> segs;
  segs.clear();
  for (const auto& s : markings_.segments) {
    const Eigen::Vector2d a = local({s.x0_m, s.y0_m});
    const Eigen::Vector2d b = local({s.x1_m, s.y1_m});
    const Eigen::Vector2d e = b - a;
    const double len2 = e.squaredNorm();
    const double u = len2 > 0 ? std::clamp(-a.dot(e) / len2, 0.0, 1.0) : 0.0;
    if ((a + u * e).norm() > reach) continue;  // its nearest point is out of reach
    segs.push_back({a, b, e, a.x() * e.y() - a.y() * e.x()});
  }
  struct Arc {
    Eigen::Vector2d c;
    double r, start, end;
    bool whole;  // a full circle: every crossing is on it (on_arc needs no angle)
  };
  thread_local std::vector<Arc> arcs;
  arcs.clear();
  for (const auto& a : markings_.arcs) {
    const Eigen::Vector2d c = local({a.cx_m, a.cy_m});
    if (c.norm() - a.radius_m > reach) continue;  // the whole circle is out of reach
    const double start = wrap_angle(a.start_rad - me.heading_rad);
    const double end = start + (a.end_rad - a.start_rad);
    // on_arc takes rel in [0, 2 pi] and accepts rel <= end - start + 1e-12.
    arcs.push_back({c, a.radius_m, start, end, 2 * kPi <= (end - start) + 1e-12});
  }
  auto on = [](const Arc& a, const Eigen::Vector2d& q) {
    return a.whole || on_arc(physics::LineArc{0, 0, a.r, a.start, a.end}, std::atan2(q.y(), q.x()));
  };
  auto keep = [&](Eigen::Vector2d p) {
    if (static_cast<int>(out.lines.size()) >= params_.max_line_points) return false;
    if (detection < 1 && chance(rng) > detection) return true;
    if (noisy) p += Eigen::Vector2d(point_noise(rng), point_noise(rng));
    out.lines.push_back(p);
    return true;
  };
  // Radial sensors: every ray's crossings, nearest first. Points are then
  // taken round-robin — the nearest crossing of each ray of pass 1, of pass 2,
  // ..., then the second crossings — so that when the cap is reached the
  // points already cover the whole circle.
  constexpr std::size_t kMaxHits = 16;
  const std::size_t rays = line_dir_.size();  // pass after pass
  thread_local std::vector<double> hit_t;
  thread_local std::vector<std::size_t> hit_n;
  if (hit_t.size() < rays * kMaxHits) hit_t.resize(rays * kMaxHits);  // no need to clear: hit_n says what is valid
  hit_n.assign(rays, 0);
  const std::vector<Eigen::Vector2d>& ray_dir = line_dir_;
  // Each circle, segment and arc is tested only by the sensors whose
  // direction lies within the angle it covers as seen from the camera (with
  // a sensor to spare on each side), in the same order per sensor as testing
  // every sensor against everything: the same points.
  const double angle_step = 2 * kPi / static_cast<double>(rays);
  auto each_ray = [&](double lo, double hi, auto&& test) {
    const auto j0 = static_cast<long>(std::floor(lo / angle_step)) - 1;
    const auto j1 = static_cast<long>(std::ceil(hi / angle_step)) + 1;
    const auto n_rays = static_cast<long>(rays);
    if (j1 - j0 + 1 >= n_rays) {
      for (std::size_t ray = 0; ray < rays; ++ray) test(ray);
      return;
    }
    auto at = static_cast<std::size_t>(((j0 % n_rays) + n_rays) % n_rays);  // one division, then wrap by hand
    for (long j = j0; j <= j1; ++j, at = at + 1 == rays ? 0 : at + 1) test(line_by_angle_[at]);
  };
  constexpr double kAllAround = 4 * kPi;
  thread_local std::vector<double> blocked;  // occlusion: nothing beyond the nearest obstacle on a ray
  blocked.assign(rays, params_.line_range_m);
  for (const Circle& c : circles) {
    each_ray(c.bearing - c.half_width, c.bearing + c.half_width,
             [&](std::size_t ray) { blocked[ray] = std::min(blocked[ray], ray_circle(ray_dir[ray], c)); });
  }
  auto add = [&](std::size_t ray, double t) {  // kept nearest first (the first kMaxHits found)
    std::size_t& n = hit_n[ray];
    if (n == kMaxHits) return;
    double* hits = &hit_t[ray * kMaxHits];
    std::size_t at = n++;
    for (; at > 0 && hits[at - 1] > t; --at) hits[at] = hits[at - 1];
    hits[at] = t;
  };
  for (const Seg& sg : segs) {
    // The angle from a to b the short way round; all around when the segment
    // passes (nearly) through the camera.
    double lo = 0;
    double hi = kAllAround;
    if (sg.a.squaredNorm() > 1e-18 && sg.b.squaredNorm() > 1e-18) {
      const double from = rough_atan2(sg.a.y(), sg.a.x());
      double turn = rough_atan2(sg.b.y(), sg.b.x()) - from;
      if (turn > kPi) turn -= 2 * kPi;
      if (turn < -kPi) turn += 2 * kPi;
      if (std::fabs(turn) < kPi - 0.01) {
        lo = from + std::min(0.0, turn);
        hi = from + std::max(0.0, turn);
      }
    }
    each_ray(lo, hi, [&](std::size_t ray) {
      // Ray origin + t dir against segment a + u (b - a).
      const Eigen::Vector2d& dir = ray_dir[ray];
      const Eigen::Vector2d& e = sg.e;
      const double den = dir.x() * e.y() - dir.y() * e.x();
      if (std::fabs(den) < 1e-12) return;
      const double t = sg.a_cross_e / den;
      const double u = (sg.a.x() * dir.y() - sg.a.y() * dir.x()) / den;
      if (t > 0 && t <= blocked[ray] && u >= 0 && u <= 1) add(ray, t);
    });
  }
  for (const Arc& a : arcs) {
    double lo = 0;
    double hi = kAllAround;
    const double d = a.c.norm();
    if (d > a.r * (1 + 1e-9) + 1e-9) {
      const double bearing = rough_atan2(a.c.y(), a.c.x());
      const double half = std::asin(a.r / d);
      lo = bearing - half;
      hi = bearing + half;
    }
    each_ray(lo, hi, [&](std::size_t ray) {
      const Eigen::Vector2d& dir = ray_dir[ray];
      const double b = dir.dot(a.c);
      const double disc = b * b - (a.c.squaredNorm() - a.r * a.r);
      if (disc < 0) return;
      for (const double t : {b - std::sqrt(disc), b + std::sqrt(disc)}) {
        if (t <= 0 || t > blocked[ray]) continue;
        if (on(a, dir * t - a.c)) add(ray, t);
      }
    });
  }
  thread_local std::vector<std::size_t> live;  // the rays with a crossing left for this round, in order
  live.clear();
  for (std::size_t ray = 0; ray < rays; ++ray) {
    ++out.line_rays;
    if (hit_n[ray] > 0) live.push_back(ray);
  }
  bool room = true;
  for (std::size_t round = 0; !live.empty() && room; ++round) {
    std::size_t still = 0;
    for (const std::size_t ray : live) {
      room = keep(ray_dir[ray] * hit_t[ray * kMaxHits + round]);
      if (!room) break;
      if (hit_n[ray] > round + 1) live[still++] = ray;
    }
    live.resize(still);
  }
  // Circular sensors: crossings of rings around the robot with the markings
  // (they see the lines a radial sensor meets only at a grazing angle).
  for (const double r : params_.circle_radii_m) {
    if (r > params_.line_range_m) continue;
    for (const Seg& s : segs) {
      const Eigen::Vector2d& e = s.e;
      const double A = e.squaredNorm();
      const double B = 2 * s.a.dot(e);
      const double C = s.a.squaredNorm() - r * r;
      const double disc = B * B - 4 * A * C;
      if (disc < 0 || A < 1e-12) continue;
      for (const double u : {(-B - std::sqrt(disc)) / (2 * A), (-B + std::sqrt(disc)) / (2 * A)}) {
        if (u < 0 || u > 1) continue;
        const Eigen::Vector2d p = s.a + u * e;
        if (!occluded(p, circles) && !keep(p)) break;
      }
    }
    for (const Arc& a : arcs) {
      // Two circles: |p| = r and |p - c| = a.r.
      const double d = a.c.norm();
      if (d < 1e-9 || d > r + a.r || d < std::fabs(r - a.r)) continue;
      const double along = (r * r - a.r * a.r + d * d) / (2 * d);
      const double h = std::sqrt(std::max(0.0, r * r - along * along));
      const Eigen::Vector2d mid = a.c * (along / d);
      const Eigen::Vector2d perp(-a.c.y() / d, a.c.x() / d);
      for (const double sign : {-1.0, 1.0}) {
        const Eigen::Vector2d p = mid + sign * h * perp;
        if (!on(a, p - a.c)) continue;
        if (!occluded(p, circles) && !keep(p)) break;
      }
    }
  }

  // --- the ball: projected to the ground, within the see limit, not occluded.
  const Eigen::Vector2d ball_local = local(scene.ball.head<2>());
  const double d_prime = ball_local.norm();
  const double h = params_.camera_height_m;
  const double h_prime = scene.ball.z() - scene.ball_radius_m;  // height above its resting height
  if (h_prime < h && d_prime > 1e-9) {
    const double d = h * d_prime / (h - h_prime);
    const bool seen =
        d < params_.ball_see_limit_m && !occluded(ball_local, circles) && (detection >= 1 || chance(rng) <= detection);
    if (seen) {
      Eigen::Vector2d p = ball_local * (d / d_prime);
      if (params_.ball_noise_m > 0) {
        const Gaussian bn(static_cast<float>(params_.ball_noise_m));
        p += Eigen::Vector2d(bn(rng), bn(rng));
      }
      out.balls.push_back(p);
    }
  }
}

}  // namespace canhil::vision_emu
