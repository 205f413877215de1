// `canhil timing SOURCE`: timing and FTT compliance of a candump log or a live
// interface. Exit status 1 when anything is violated (for a team's own CI), and
// when the capture cannot show the timing (no frames, no trigger message,
// shorter than the longest period) unless --allow-empty.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/physics/svg_plot.hpp"
#include "canhil/timing/analysis.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "log_file.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

double number(const std::optional<std::string>& v, const char* name, double fallback) {
  if (!v) return fallback;
  try {
    std::size_t used = 0;
    const double d = std::stod(*v, &used);
    if (used == v->size()) return d;
  } catch (const std::exception&) {
  }
  throw UsageError(std::string(name) + " takes a number, got \"" + *v + "\"");
}

}  // namespace

int run_timing(Args& args, const std::optional<std::string>& dbc) {
  if (args.flag("--analyse") || args.flag("--analyze")) return run_timing_analyse(args, dbc);
  const bool json = args.flag("--json");
  const bool allow_empty = args.flag("--allow-empty");
  const auto svg = args.option("--svg");
  timing::TimingConfig cfg;
  cfg.ftt.elementary_cycle = std::chrono::duration_cast<Nanos>(
      std::chrono::duration<double, std::milli>(number(args.option("--ec-ms"), "--ec-ms", 10)));
  cfg.ftt.bit_rate = static_cast<std::uint32_t>(number(args.option("--bit-rate"), "--bit-rate", 1'000'000));
  cfg.ftt.stamps = stamps_option(args);
  cfg.window_slack = std::chrono::duration_cast<Nanos>(
      std::chrono::duration<double, std::micro>(number(args.option("--slack-us"), "--slack-us", 0)));
  const double seconds = number(args.option("--seconds"), "--seconds", 10);
  const std::vector<std::string> words = args.positionals();
  if (words.size() != 2) throw UsageError("timing needs one SOURCE: a candump log file or an interface (e.g. vcan0)");
  const std::string& source = words[1];
  auto set = frames::MessageSet::create(load_chosen_dbc(dbc));
  timing::TimingAnalyzer analyzer(set, cfg);
  if (std::filesystem::exists(source)) {
    for_each_log_entry(source, [&](const frames::LogEntry& e) { analyzer.add({e.frame, e.time}); });
  } else {
    auto bus = can_nodes::SocketCanBus::open(source);
    bus->set_error_mask(frames::kErrorClassMask);  // error frames count toward the load and the report
    const can_nodes::WallClock clock;
    const Nanos end = clock.now() + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(seconds));
    stop_on_signals();
    if (!json)
      std::fprintf(stderr, "canhil timing: listening on %s for %.0f s (Ctrl-C stops early)\n", source.c_str(), seconds);
    while (!g_stop && clock.now() < end) {
      if (!bus->wait_readable(std::chrono::milliseconds(100))) continue;
      while (auto f = bus->receive()) analyzer.add(*f);
    }
  }
  const timing::TimingReport report = analyzer.finish();
  std::printf("%s%s", json ? timing::format_json(report).c_str() : timing::format_table(report).c_str(),
              json ? "\n" : "");
  if (svg) {
    // Interval histograms, relative to each periodic message's period.
    physics::Plot plot{"Intervals of the periodic messages", "interval / specified period", "frames", {}};
    for (const auto& m : report.messages) {
      if (m.kind == frames::FttKind::kAsync || m.intervals.empty()) continue;
      std::map<int, int> bins;  // 0.01 wide
      for (auto i : m.intervals)
        ++bins[static_cast<int>(
            std::lround(100.0 * static_cast<double>(i.count()) / static_cast<double>(m.spec.count())))];
      physics::Series s{m.name, {}, {}};
      for (const auto& [b, c] : bins) {
        s.x.push_back(b / 100.0);
        s.y.push_back(c);
      }
      plot.series.push_back(std::move(s));
    }
    std::ofstream out(*svg);
    out << physics::svg_plots({plot});
  }
  if (!report.capture_ok() && !allow_empty) {
    // Its own message and status: a team's CI must not read a broken capture as clean timing.
    for (const auto& [kind, text] : report.capture_problems) {
      std::fprintf(stderr, "canhil timing: %s: %s\n", source.c_str(), text.c_str());
    }
    std::fprintf(stderr, "canhil timing: no timing verdict on this capture (--allow-empty accepts it)\n");
    return 1;
  }
  return report.ok() ? 0 : 1;
}

}  // namespace canhil::app
