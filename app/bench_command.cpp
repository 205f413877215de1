// `canhil bench`: the figures a team checks on its own machine, in one run.
// Built so far: the real-time factor of the five-robot scenario in virtual
// time with everything on (nodes, buses, physics, vision, handlers, agents,
// trace recording); target at least 100x. Real-time release jitter and vcan
// throughput need SocketCAN and are measured by bench/handler_latency.sh and
// the vcan tests (docs/performance.md).
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/virtual_run.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"

namespace canhil::app {
namespace {

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace

std::filesystem::path shipped_scenario(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    fs::path installed = exe.parent_path().parent_path() / "share" / "canhil" / "scenarios" / name;
    if (fs::exists(installed, ec)) return installed;
  }
  return fs::path(CANHIL_SOURCE_SCENARIOS) / name;
}

int run_bench(Args& args, const std::optional<std::string>& dbc) {
  const double seconds = number_option(args, "--seconds", 20);
  const auto config = args.option("--config");
  if (args.positionals().size() != 1) throw UsageError("bench takes no other arguments");
  if (!(seconds > 0)) throw UsageError("--seconds takes a number above 0");
  if (std::getenv("RTDB_KEY") == nullptr) {
    setenv("RTDB_KEY", std::to_string(0x57000000 + ((getpid() & 0xFFFF) << 8)).c_str(), 1);
  }
  const std::filesystem::path path = config ? std::filesystem::path(*config) : shipped_scenario("five_robots.toml");
  const emulator::Scenario sc = emulator::load_scenario(path);
  const emulator::VirtualRunConfig cfg =
      emulator::virtual_run_config(sc, frames::MessageSet::create(load_chosen_dbc(dbc)));
  std::printf("canhil bench: %s, %zu robot(s), %zu obstacle(s), %g s of virtual time\n", path.string().c_str(),
              sc.world.robots.size(), sc.world.obstacles.size(), seconds);
  const double cpu0 = cpu_seconds();
  const auto wall0 = std::chrono::steady_clock::now();
  emulator::VirtualRun run(cfg);
  run.run_for(std::chrono::duration_cast<frames::Nanos>(std::chrono::duration<double>(seconds)));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double cpu = cpu_seconds() - cpu0;
  std::uint64_t frames = 0;
  for (const auto& o : run.outcomes()) frames += o.frames;
  const double factor = seconds / wall;
  std::printf(
      "  real-time factor, virtual time, everything on: %.0fx (wall %.3f s, CPU %.3f s = %.0fx of one core)"
      "  target >= 100x: %s\n",
      factor, wall, cpu, seconds / cpu, factor >= 100 ? "met" : "MISSED");
  std::printf("  frames on the buses: %llu (%.0f per simulated second)\n", static_cast<unsigned long long>(frames),
              static_cast<double>(frames) / seconds);
  std::printf("  release jitter and vcan throughput: need SocketCAN; see docs/performance.md\n");
  return factor >= 100 ? 0 : 1;
}

}  // namespace canhil::app
