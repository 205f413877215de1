#include <charconv>
#include <cstdio>
#include <fstream>
#include <iostream>

#include "canhil/frames/describe.hpp"
#include "canhil/physics/config.hpp"
#include "canhil/physics/experiments.hpp"
#include "canhil/physics/svg_plot.hpp"
#include "canhil/vision_emu/runner.hpp"
#include "canhil/vision_emu/svg.hpp"
#include "commands.hpp"

namespace canhil::app {
namespace {

double to_number(const std::string& option, const std::string& text) {
  double v = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || p != text.data() + text.size()) {
    throw UsageError(option + " takes a number, got \"" + text + "\"");
  }
  return v;
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", v);
  return buf;
}

void print_table(const physics::ExperimentResult& r) {
  std::printf("%s: %s\n\n", r.name.c_str(), r.description.c_str());
  for (const auto& c : r.columns) std::printf("%18s", c.c_str());
  std::printf("\n");
  for (const auto& row : r.rows) {
    for (double v : row) std::printf("%18s", number_text(v).c_str());
    std::printf("\n");
  }
  std::printf("\n");
  for (const auto& f : r.figures) {
    std::printf("  %-32s %12s   target %-22s %s\n", f.name.c_str(), number_text(f.value).c_str(),
                f.target.empty() ? "-" : f.target.c_str(), f.target.empty() ? "" : (f.met ? "met" : "MISSED"));
  }
}

void print_json(const physics::ExperimentResult& r) {
  using frames::json_quote;
  std::string out =
      "{\"experiment\":" + json_quote(r.name) + ",\"description\":" + json_quote(r.description) + ",\"columns\":[";
  for (std::size_t i = 0; i < r.columns.size(); ++i) out += (i ? "," : "") + json_quote(r.columns[i]);
  out += "],\"rows\":[";
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    out += i ? ",[" : "[";
    for (std::size_t j = 0; j < r.rows[i].size(); ++j) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.9g", r.rows[i][j]);
      out += (j ? "," : "") + std::string(buf);
    }
    out += "]";
  }
  out += "],\"figures\":[";
  for (std::size_t i = 0; i < r.figures.size(); ++i) {
    const auto& f = r.figures[i];
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", f.value);
    out += std::string(i ? "," : "") + "{\"name\":" + json_quote(f.name) + ",\"value\":" + buf +
           ",\"target\":" + json_quote(f.target) + ",\"met\":" + (f.met ? "true" : "false") + "}";
  }
  out += "],\"all_met\":" + std::string(r.all_met() ? "true" : "false") + "}";
  std::printf("%s\n", out.c_str());
}

// `canhil experiment vision`: one frame of one robot in a busy scene.
int vision_experiment(const physics::WorldParams& base, int robot, const std::optional<std::string>& svg, bool json,
                      double noise) {
  physics::WorldParams p = base;
  if (p.robots.empty()) {
    p.robots = {{-3.0, 0.0, -90}, {0.0, 2.0, 0}, {2.5, -2.0, 45}, {4.5, 1.0, 90}, {-5.0, -3.0, -45}};
    const std::vector<std::pair<double, double>> obstacles = {
        {-1.5, 0.35}, {1.0, -1.2}, {3.0, 3.0}, {-2.0, -3.0}, {6.0, -1.0}};
    for (const auto& [x, y] : obstacles) p.obstacles.push_back(physics::ObstaclePlacement{{x, y, 0}, {}});
    p.ball_start = {0.2, 0.9, p.ball.radius_m};
  }
  physics::World world(p);
  vision_emu::VisionParams vp;
  vp.point_noise_m = noise;
  vp.ball_noise_m = noise;
  const vision_emu::Vision vision(vp, world.markings());
  const vision_emu::Scene scene = vision_emu::snapshot(world);
  const auto r = static_cast<std::size_t>(robot);
  if (r >= scene.robots.size())
    throw UsageError("--robot " + std::to_string(r) + ": the scene has " + std::to_string(scene.robots.size()) +
                     " robots");
  vision_emu::NoiseEngine rng(vp.seed);
  const vision_emu::VisionFrame f = vision.see(scene, r, rng);
  if (json) {
    std::printf(
        "{\"experiment\":\"vision\",\"robot\":%zu,\"line_points\":%zu,\"obstacle_points\":%zu,\"balls\":%zu,\"line_"
        "rays\":%d}\n",
        r, f.lines.size(), f.obstacles.size(), f.balls.size(), f.line_rays);
  } else {
    std::printf("vision: robot %zu at (%.2f, %.2f), %zu robots, %zu obstacles\n", r, scene.robots[r].x_m,
                scene.robots[r].y_m, scene.robots.size(), scene.obstacles.size());
    std::printf("  line points      %4zu  (%d radial sensors in %d passes, %zu circular sensors, cap %d)\n",
                f.lines.size(), vp.line_sensors, vp.line_passes, vp.circle_radii_m.size(), vp.max_line_points);
    std::printf("  obstacle points  %4zu  (%d radial sensors)\n", f.obstacles.size(), vp.obstacle_sensors);
    std::printf("  balls            %4zu", f.balls.size());
    if (!f.balls.empty()) std::printf("  at (%.3f, %.3f) m in the robot frame", f.balls[0].x(), f.balls[0].y());
    std::printf("\n");
  }
  if (svg) {
    std::ofstream out(*svg);
    out << vision_emu::render_svg(vision, scene, r, f);
    if (!out) throw UsageError("cannot write " + *svg);
    if (!json) std::printf("frame drawn in %s\n", svg->c_str());
  }
  return 0;
}

}  // namespace

int run_experiment(Args& args) {
  const bool json = args.flag("--json");
  const auto svg = args.option("--svg");
  const auto config = args.option("--config");
  physics::ExperimentOptions options;
  if (const auto v = args.option("--height")) options.height_m = to_number("--height", *v);
  if (const auto v = args.option("--speed")) options.speed_mps = to_number("--speed", *v);
  if (const auto v = args.option("--power")) options.power = static_cast<int>(to_number("--power", *v));
  if (const auto v = args.option("--vx")) options.vx_mps = to_number("--vx", *v);
  if (const auto v = args.option("--vy")) options.vy_mps = to_number("--vy", *v);
  if (const auto v = args.option("--va")) options.va_radps = to_number("--va", *v);
  if (const auto v = args.option("--duration")) options.duration_s = to_number("--duration", *v);
  const auto robot_text = args.option("--robot");
  const auto noise_text = args.option("--noise");
  if (args.flag("--low")) options.low = true;
  if (args.flag("--high")) options.low = false;
  const std::vector<std::string> words = args.positionals();
  if (words.size() != 2) {
    std::string names;
    for (const auto& n : physics::experiment_names()) names += (names.empty() ? "" : ", ") + n;
    throw UsageError("experiment needs one name: " + names + ", vision");
  }
  const physics::WorldParams params = config ? physics::load_world_params(*config) : physics::WorldParams{};
  if (words[1] == "vision") {
    const int robot = robot_text ? static_cast<int>(to_number("--robot", *robot_text)) : 0;
    if (robot < 0) throw UsageError("--robot takes a robot number, 0 or more");
    return vision_experiment(params, robot, svg, json, noise_text ? to_number("--noise", *noise_text) : 0.0);
  }
  const physics::ExperimentResult result = physics::run_experiment(words[1], params, options);
  if (json) {
    print_json(result);
  } else {
    print_table(result);
  }
  if (svg) {
    std::ofstream out(*svg);
    out << physics::svg_plots(result.plots);
    if (!out) throw UsageError("cannot write " + *svg);
    if (!json) std::printf("\nplot written to %s\n", svg->c_str());
  }
  return result.all_met() ? 0 : 1;
}

}  // namespace canhil::app
