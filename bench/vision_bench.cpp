// vision_bench — microseconds per robot-frame of the emulated vision in a
// scene of 5 robots, 5 obstacles and the ball, everything on (all sensors,
// occlusion, noise, detection probability). Target (issue 6): at most 20 us
// (the older simulator needed 3 500 us for obstacles alone).
#include <benchmark/benchmark.h>

#include "canhil/vision_emu/runner.hpp"

namespace {

using namespace canhil;

void BM_VisionRobotFrame(benchmark::State& state) {
  physics::WorldParams p;
  p.robots = {{-3.0, 0.0, -90}, {0.0, 2.0, 0}, {2.5, -2.0, 45}, {4.5, 1.0, 90}, {-5.0, -3.0, -45}};
  for (const auto& [x, y] :
       std::vector<std::pair<double, double>>{{-1.5, 0.35}, {1.0, -1.2}, {3.0, 3.0}, {-2.0, -3.0}, {6.0, -1.0}}) {
    p.obstacles.push_back(physics::ObstaclePlacement{{x, y, 0}, {}});
  }
  p.ball_start = {0.5, -0.5, p.ball.radius_m};
  physics::World world(p);
  vision_emu::VisionParams vp;
  vp.point_noise_m = 0.01;
  vp.ball_noise_m = 0.02;
  vp.detection_probability = 0.95;
  const vision_emu::Vision vision(vp, world.markings());
  const vision_emu::Scene scene = vision_emu::snapshot(world);
  vision_emu::NoiseEngine rng(1);
  std::size_t robot = 0;
  std::size_t points = 0;
  vision_emu::VisionFrame f;
  for (auto _ : state) {
    vision.see(scene, robot, rng, f);
    points += f.lines.size() + f.obstacles.size();
    benchmark::DoNotOptimize(f);
    robot = (robot + 1) % scene.robots.size();
  }
  state.counters["points_per_frame"] = static_cast<double>(points) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_VisionRobotFrame)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
