// `canhil view WORLD_LOG [--trace TRACE]`: a recorded run in the web viewer
// (viewer::ReplayFeed): the page plays the world log with a timeline and
// shows the trace's frames around its cursor. Serves until Ctrl-C (or --duration).
#include <atomic>

#include "canhil/emulator/scenario.hpp"
#include "canhil/viewer/replay_feed.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "run_view.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
int run_view(Args& args, const std::optional<std::string>& dbc) {
  const auto trace = args.option("--trace");
  const auto config = args.option("--config");
  const std::optional<double> duration = optional_number(args, "--duration");
  ViewChoice view = view_options(args);
  if (!view.on) throw UsageError("canhil view is the viewer; --no-view leaves nothing to do");
  if (args.positionals().size() != 2) throw UsageError("give one world log (canhil run --world-log FILE)");
  if (duration && !(*duration > 0)) throw UsageError("--duration takes seconds above 0");
  const std::string world_log = args.positionals()[1];
  emulator::Scenario scenario;
  try {
    scenario =
        emulator::load_scenario(config ? std::filesystem::path(*config) : emulator::shipped_scenario("one_robot.toml"));
  } catch (const SetupError& e) {
    throw UsageError(std::string(config ? *config + ": " : "") + e.what());
  }
  const auto messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  std::unique_ptr<viewer::ReplayFeed> feed;
  try {
    feed = std::make_unique<viewer::ReplayFeed>(
        world_log, trace ? std::optional<std::filesystem::path>(*trace) : std::nullopt, scenario.world, messages);
  } catch (const SetupError& e) {
    throw UsageError(e.what());
  }
  std::printf("canhil view: %s: %zu rows, %zu robot(s), %zu event(s)%s\n", world_log.c_str(), feed->rows(),
              feed->robots(), feed->events().size(), trace ? (", trace " + *trace).c_str() : "");
  const auto server = start_viewer(view, *feed, "canhil view", stdout, /*required=*/true);
  stop_on_signals();
  serve_until(g_stop, duration.value_or(1e9));
  return 0;
}

}  // namespace canhil::app
