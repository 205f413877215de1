// `canhil timing --analyse [TRACE]`: what the message set allows (frame
// times, the FTT schedule and its test, sporadic and native response bounds,
// what-if limits), and with a TRACE every observation next to its bound. Exit
// status 1 when the set is not schedulable or an observation passes its bound.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "canhil/timing/bound_check.hpp"
#include "canhil/timing/bus_analysis.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "log_file.hpp"

namespace canhil::app {
namespace {

void positive(const std::optional<double>& v, const char* name) {
  if (v && !(*v > 0)) throw UsageError(std::string(name) + " takes a positive number");
}

}  // namespace

int run_timing_analyse(Args& args, const std::optional<std::string>& dbc) {
  const bool json = args.flag("--json");
  const auto svg = args.option("--svg");
  const auto ec_ms = optional_number(args, "--ec-ms");
  const auto bit_rate = optional_number(args, "--bit-rate");
  const auto window_us = optional_number(args, "--sync-window-us");
  const auto guard_us = optional_number(args, "--guard-us");
  const double slack_us = number_option(args, "--slack-us", 0);
  const frames::StampAt stamps = stamps_option(args);
  positive(ec_ms, "--ec-ms");
  positive(bit_rate, "--bit-rate");
  positive(window_us, "--sync-window-us");
  if (guard_us && *guard_us < 0) throw UsageError("--guard-us takes a number, 0 or more");
  std::vector<std::string> added;
  while (auto a = args.option("--add")) added.push_back(*a);
  timing::AnalysisConfig config;
  while (auto c = args.option("--copies")) config.copies_of.push_back(*c);
  config.what_if = !args.flag("--no-what-if");
  const std::vector<std::string> words = args.positionals();
  if (words.size() > 2) throw UsageError("timing --analyse takes at most one TRACE (a candump log)");

  frames::Database db = load_chosen_dbc(dbc);
  timing::BusSet set = timing::read_bus_set(db);
  for (const std::string& a : added) timing::add_message(set, a);
  for (const std::string& a : added) {
    const std::string name = a.substr(0, a.find_first_of(" \t"));
    if (std::find(config.copies_of.begin(), config.copies_of.end(), name) == config.copies_of.end())
      config.copies_of.push_back(name);
  }
  // The EC and bit rate: the options, else the DBC's (the trigger message's
  // period, the Baudrate attribute), else canhil's defaults.
  Nanos ec = config.ftt.elementary_cycle;
  for (const timing::BusMessage& m : set.messages) {
    if (m.kind == frames::FttKind::kTrigger) ec = m.period;
  }
  if (ec_ms) ec = from_ms(*ec_ms);
  config.ftt.elementary_cycle = ec;
  if (const auto baud = db.baudrate()) config.ftt.bit_rate = *baud;
  if (bit_rate) config.ftt.bit_rate = static_cast<std::uint32_t>(*bit_rate);
  config.ftt.stamps = stamps;
  if (guard_us) config.ftt.sync_window_guard = from_ms(*guard_us / 1e3);
  if (window_us) config.sync_window = from_ms(*window_us / 1e3);

  const timing::BusAnalysis analysis = timing::analyse_bus(set, config);
  std::optional<timing::BoundReport> bounds;
  if (words.size() == 2) {
    const std::string& source = words[1];
    if (!std::filesystem::exists(source)) throw UsageError("timing --analyse: no trace file " + source);
    std::shared_ptr<const frames::MessageSet> messages;
    if (set.ftt) messages = frames::MessageSet::create(db);
    timing::BoundChecker checker(analysis, messages, from_ms(slack_us / 1e3));
    for_each_log_entry(source, [&](const frames::LogEntry& e) { checker.add({e.frame, e.time}); });
    bounds = checker.finish();
  }
  if (json) {
    std::printf("{\"analysis\":%s", timing::format_analysis_json(analysis).c_str());
    if (bounds) std::printf(",\"trace\":%s", timing::format_bounds_json(*bounds).c_str());
    std::printf("}\n");
  } else {
    std::printf("%s", timing::format_analysis(analysis).c_str());
    if (bounds) std::printf("%s", timing::format_bounds(*bounds).c_str());
  }
  if (svg) {
    std::ofstream out(*svg);
    out << timing::format_analysis_svg(analysis);
    if (!out) throw SetupError("cannot write " + *svg);
  }
  return analysis.schedulable() && (!bounds || bounds->ok()) ? 0 : 1;
}

}  // namespace canhil::app
