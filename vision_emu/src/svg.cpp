#include "canhil/vision_emu/svg.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

namespace canhil::vision_emu {

std::string render_svg(const Vision& vision, const Scene& scene, std::size_t robot, const VisionFrame& frame) {
  const physics::FieldMarkings& m = vision.markings();
  double hx = 0, hy = 0;
  for (const auto& s : m.segments) {
    hx = std::max({hx, std::fabs(s.x0_m), std::fabs(s.x1_m)});
    hy = std::max({hy, std::fabs(s.y0_m), std::fabs(s.y1_m)});
  }
  const double margin = 1.0;
  const double scale = 60;  // px per metre
  const double w = 2 * (hx + margin) * scale;
  const double h = 2 * (hy + margin) * scale;
  auto X = [&](double x) { return (x + hx + margin) * scale; };
  auto Y = [&](double y) { return (hy + margin - y) * scale; };
  std::ostringstream os;
  os.precision(4);
  os << "<svg xmlns='http://www.w3.org/2000/svg' width='" << w << "' height='" << h + 30
     << "' font-family='sans-serif' font-size='14'>\n<rect width='100%' height='100%' fill='#2e7d32'/>\n";
  const double lw = m.line_width_m * scale;
  for (const auto& s : m.segments) {
    os << "<line x1='" << X(s.x0_m) << "' y1='" << Y(s.y0_m) << "' x2='" << X(s.x1_m) << "' y2='" << Y(s.y1_m)
       << "' stroke='white' stroke-width='" << lw << "'/>\n";
  }
  for (const auto& a : m.arcs) {
    os << "<path fill='none' stroke='white' stroke-width='" << lw << "' d='";
    const int n = 48;
    for (int i = 0; i <= n; ++i) {
      const double t = a.start_rad + (a.end_rad - a.start_rad) * i / n;
      os << (i ? " L " : "M ") << X(a.cx_m + a.radius_m * std::cos(t)) << ' ' << Y(a.cy_m + a.radius_m * std::sin(t));
    }
    os << "'/>\n";
  }
  const kinematics::Pose& me = scene.robots.at(robot);
  // Occlusion wedges: from the camera, tangent to each obstacle, outwards.
  auto wedge = [&](const Eigen::Vector2d& c, double r) {
    const Eigen::Vector2d d = c - Eigen::Vector2d(me.x_m, me.y_m);
    const double dist = d.norm();
    if (dist <= r) return;
    const double half = std::asin(r / dist);
    const double b = std::atan2(d.y(), d.x());
    const double far = 20;
    const double near = std::sqrt(dist * dist - r * r);
    os << "<polygon fill='black' fill-opacity='0.25' points='";
    for (const double s : {-1.0, 1.0}) {
      os << X(me.x_m + near * std::cos(b + s * half)) << ',' << Y(me.y_m + near * std::sin(b + s * half)) << ' ';
    }
    os << X(me.x_m + far * std::cos(b + half)) << ',' << Y(me.y_m + far * std::sin(b + half)) << ' '
       << X(me.x_m + far * std::cos(b - half)) << ',' << Y(me.y_m + far * std::sin(b - half)) << "'/>\n";
  };
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    if (i != robot) wedge({scene.robots[i].x_m, scene.robots[i].y_m}, scene.robot_radius_m);
  }
  for (const auto& o : scene.obstacles) wedge(o.centre, o.radius_m);
  // The line sensors' rays.
  const VisionParams& p = vision.params();
  for (int pass = 0; pass < p.line_passes; ++pass) {
    for (int k = 0; k < p.line_sensors; ++k) {
      const double a = 2 * std::numbers::pi * (k + static_cast<double>(pass) / p.line_passes) / p.line_sensors;
      const Eigen::Vector2d end = Vision::to_world(me, {p.line_range_m * std::cos(a), p.line_range_m * std::sin(a)});
      os << "<line x1='" << X(me.x_m) << "' y1='" << Y(me.y_m) << "' x2='" << X(end.x()) << "' y2='" << Y(end.y())
         << "' stroke='yellow' stroke-opacity='0.25' stroke-width='1'/>\n";
    }
  }
  for (const double r : p.circle_radii_m) {
    os << "<circle cx='" << X(me.x_m) << "' cy='" << Y(me.y_m) << "' r='" << r * scale
       << "' fill='none' stroke='yellow' stroke-opacity='0.25'/>\n";
  }
  // Bodies.
  for (std::size_t i = 0; i < scene.robots.size(); ++i) {
    const auto& r = scene.robots[i];
    const double f = r.heading_rad + std::numbers::pi / 2;
    os << "<circle cx='" << X(r.x_m) << "' cy='" << Y(r.y_m) << "' r='" << scene.robot_radius_m * scale << "' fill='"
       << (i == robot ? "#1565c0" : "#37474f") << "' stroke='white'/>\n<line x1='" << X(r.x_m) << "' y1='" << Y(r.y_m)
       << "' x2='" << X(r.x_m + 0.35 * std::cos(f)) << "' y2='" << Y(r.y_m + 0.35 * std::sin(f))
       << "' stroke='white' stroke-width='3'/>\n";
  }
  for (const auto& o : scene.obstacles) {
    os << "<circle cx='" << X(o.centre.x()) << "' cy='" << Y(o.centre.y()) << "' r='" << o.radius_m * scale
       << "' fill='black'/>\n";
  }
  os << "<circle cx='" << X(scene.ball.x()) << "' cy='" << Y(scene.ball.y()) << "' r='" << scene.ball_radius_m * scale
     << "' fill='orange' stroke='black'/>\n";
  // What was seen (robot frame back to the world).
  auto dots = [&](const std::vector<Eigen::Vector2d>& pts, const char* colour, double radius) {
    for (const auto& l : pts) {
      const Eigen::Vector2d w2 = Vision::to_world(me, l);
      os << "<circle cx='" << X(w2.x()) << "' cy='" << Y(w2.y()) << "' r='" << radius << "' fill='" << colour
         << "'/>\n";
    }
  };
  dots(frame.lines, "#e91e63", 4);
  dots(frame.obstacles, "#00e5ff", 3);
  dots(frame.balls, "red", 7);
  os << "<text x='10' y='" << h + 22 << "' fill='black'>robot " << robot << ": " << frame.lines.size()
     << " line points (magenta), " << frame.obstacles.size() << " obstacle points (cyan), " << frame.balls.size()
     << " ball (red); shaded: occlusion wedges</text>\n</svg>\n";
  return os.str();
}

}  // namespace canhil::vision_emu
