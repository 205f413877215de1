#include "bench_jobs.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "canhil/emulator/match.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/external/match_workers.hpp"

namespace canhil::app {

bool bench_jobs(const std::optional<std::string>& config, double seconds,
                const std::shared_ptr<const frames::MessageSet>& messages) {
  const std::filesystem::path path =
      config ? std::filesystem::path(*config) : emulator::shipped_scenario("two_teams.toml");
  const emulator::Scenario scenario = emulator::load_scenario(path);
  emulator::SessionOptions options;
  options.messages = messages;
  emulator::MatchOptions match;
  match.halves = 1;
  // Halves short enough that eight take about --seconds on one core (a ten-robot half runs near 80x).
  match.half_s = std::clamp(seconds * 80 / 8, 1.0, 600.0);
  constexpr int kHalves = 8;
  std::vector<std::uint64_t> seeds;
  seeds.reserve(kHalves);
  for (int k = 0; k < kHalves; ++k) seeds.push_back(scenario.seed + static_cast<std::uint64_t>(k));
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  std::printf("canhil bench: match halves per wall-clock minute, %s, %d halves of %.0f s, --jobs 1 and --jobs %u\n",
              path.filename().c_str(), kHalves, match.half_s, std::min(2U, cores));
  std::atomic<bool> stop{false};
  auto rate = [&](int workers) {
    external::MatchJobs jobs;
    jobs.play = [&](int, std::uint64_t seed, const std::function<void(double)>&) {
      emulator::MatchOptions this_match = match;
      this_match.overrides.seed = seed;
      const emulator::MatchResult r = emulator::play_match(scenario, options, this_match);
      return std::to_string(seed) + " played " + std::to_string(r.virtual_s);
    };
    jobs.failed = [](std::uint64_t seed, const std::string& why) { return std::to_string(seed) + " failed " + why; };
    int halves = 0;
    jobs.done = [&](const std::string& r) { halves += r.find(" failed ") == std::string::npos ? 1 : 0; };
    const auto t0 = std::chrono::steady_clock::now();
    external::play_in_workers(seeds, workers, jobs, stop);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double per_minute = halves * 60 / wall;
    std::printf("  --jobs %d: %d halves in %6.1f s of wall time, %6.1f halves per minute\n", workers, halves, wall,
                per_minute);
    return per_minute;
  };
  const double one = rate(1);
  const double two = rate(2);
  const double ratio = one > 0 ? two / one : 0;
  const bool met = ratio >= 1.8;
  std::printf("  throughput, --jobs 2 / --jobs 1: %.2fx  target >= 1.8x: %s%s\n", ratio, met ? "met" : "MISSED",
              cores < 2 ? " (this machine has one core)" : "");
  return met;
}

}  // namespace canhil::app
