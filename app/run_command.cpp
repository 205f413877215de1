// `canhil run --virtual-time --duration S [--config WORLD.toml] [--trace FILE]`:
// the whole loop in virtual time (emulator/virtual_run.hpp). Real-time mode and
// scenarios with interfaces, fault injection and the world log come next.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/emulator/virtual_run.hpp"
#include "canhil/physics/config.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"

namespace canhil::app {

int run_run(Args& args, const std::optional<std::string>& dbc) {
  const bool virtual_time = args.flag("--virtual-time");
  const auto config = args.option("--config");
  const auto trace = args.option("--trace");
  const auto duration_text = args.option("--duration");
  const auto power_text = args.option("--kick-power");
  if (args.positionals().size() != 1) throw UsageError("run takes no other arguments");
  if (!virtual_time) {
    throw UsageError(
        "only --virtual-time is built so far; for real time run the emulator with `canhil nodes --iface vcan0`");
  }
  double duration = 20;
  int power = 40;
  try {
    if (duration_text) duration = std::stod(*duration_text);
    if (power_text) power = std::stoi(*power_text);
  } catch (const std::exception&) {
    throw UsageError("--duration and --kick-power take numbers");
  }
  if (std::getenv("RTDB_KEY") == nullptr) {
    // A run of its own: RTDB keys of this process, so it never meets a live robot's database.
    setenv("RTDB_KEY", std::to_string(0x58000000 + ((getpid() & 0xFFFF) << 8)).c_str(), 1);
  }
  emulator::VirtualRunConfig cfg;
  cfg.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  if (config) cfg.world = physics::load_world_params(*config);
  if (cfg.world.robots.empty()) {
    cfg.world.robots = {physics::Placement{-3.0, 0.0, -90}};  // facing the opponent goal (+x)
    cfg.world.ball_start = {-1.0, 1.0, cfg.world.ball.radius_m};
  }
  cfg.kick_power = power;
  emulator::VirtualRun run(cfg);
  std::printf("canhil run: %zu robot(s), virtual time, %.0f s\n", cfg.world.robots.size(), duration);
  const auto step = std::chrono::seconds(1);
  const auto total = std::chrono::duration_cast<frames::Nanos>(std::chrono::duration<double>(duration));
  while (run.now() < total) {
    run.run_for(std::min<frames::Nanos>(step, total - run.now()));
    const Eigen::Vector3d b = run.world().ball_position();
    const auto o = run.outcomes();
    std::printf("  t=%5.1f s  ball (%6.2f, %5.2f)", std::chrono::duration<double>(run.now()).count(), b.x(), b.y());
    for (std::size_t r = 0; r < o.size(); ++r) {
      std::printf("  robot %zu (%5.2f, %5.2f) kicks %d", r, o[r].pose.x_m, o[r].pose.y_m, o[r].kicks);
    }
    std::printf("\n");
  }
  if (trace) {
    std::ofstream out(*trace);
    out << run.trace();
    if (!out) throw UsageError("cannot write " + *trace);
    std::printf("trace written to %s (candump log; check it with `canhil timing %s`)\n", trace->c_str(),
                trace->c_str());
  }
  std::uint64_t bad = 0;
  for (const auto& o : run.outcomes()) bad += o.bad_frames;
  std::printf("canhil run: done; bad frames counted by the nodes: %llu\n", static_cast<unsigned long long>(bad));
  return 0;
}

}  // namespace canhil::app
