// physics_bench — one 10 ms world step (all its substeps) with 5 robots,
// 5 obstacles and the ball. Target (issue 3): at most 150 us on these machines.
// The robots drive in circles and the ball rolls, so contacts change every step.
#include <benchmark/benchmark.h>

#include <cmath>

#include "canhil/kinematics/omni.hpp"
#include "canhil/physics/world.hpp"

namespace {

using namespace canhil::physics;

WorldParams scene(bool movable_obstacles, int substeps = 0, int iterations = 0) {
  WorldParams p;
  if (substeps > 0) p.simulation.substeps = substeps;
  if (iterations > 0) p.simulation.solver_iterations = iterations;
  for (int i = 0; i < 5; ++i) p.robots.push_back(Placement{-4.0 + 2.0 * i, -2.0, 90.0 * i});
  for (int i = 0; i < 5; ++i) {
    ObstaclePlacement o;
    o.at = Placement{-4.0 + 2.0 * i, 2.5, 0};
    o.params.movable = movable_obstacles;
    p.obstacles.push_back(o);
  }
  p.ball_start = {0, 0, p.ball.radius_m};
  return p;
}

void BM_WorldStep(benchmark::State& state) {
  World w(scene(state.range(0) != 0, static_cast<int>(state.range(1)), static_cast<int>(state.range(2))));
  w.place_ball({0, 0, w.params().ball.radius_m}, {1.5, 0.7, 0});
  const canhil::kinematics::OmniKinematics k(w.params().robot.geometry);
  for (std::size_t r = 0; r < w.robot_count(); ++r) {
    const auto ws = k.inverse({0.3, 0.8, 0.6});
    for (int n = 0; n < 3; ++n) w.robot(r).set_wheel_speed(n, ws[static_cast<std::size_t>(n)]);
  }
  for (int i = 0; i < 50; ++i) w.step();  // contacts settled
  for (auto _ : state) {
    w.step();
    benchmark::DoNotOptimize(w.ball_position());
  }
  state.counters["substeps"] = w.params().simulation.substeps;
  state.counters["realtime_factor"] = benchmark::Counter(
      w.params().simulation.step_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
// Defaults first; then the substep / solver-iteration trade-off for reference.
BENCHMARK(BM_WorldStep)
    ->ArgsProduct({{0, 1}, {0}, {0}})
    ->ArgNames({"movable_obstacles", "substeps", "iterations"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WorldStep)
    ->ArgsProduct({{1}, {1, 2, 5}, {10, 20}})
    ->ArgNames({"movable_obstacles", "substeps", "iterations"})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
