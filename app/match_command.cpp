// `canhil match SCENARIO [--halves 2] [--half-minutes 10] [--repeat N]
// [--seed S] [--json] [--quiet] [--external [--process CMD]... [--logs DIR]
// [--answer-limit S]]`: whole matches of a two-team scenario in virtual time
// (emulator/match.hpp), one seed per match (S, S+1, ...), and a table per
// match and over all of them: score, possession, shots, kicks, faults and FTT
// violations per team. A progress bar on a terminal's stderr. With
// --external the teams' own processes play (match_external.hpp).
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/external_driver.hpp"
#include "canhil/emulator/match.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "match_external.hpp"
#include "run_external.hpp"
#include "team_processes.hpp"

namespace canhil::app {
namespace {

std::atomic<bool> g_stop_match{false};
extern "C" void stop_match(int) { g_stop_match = true; }

// Whole numbers only, in a range.
long whole(Args& args, const std::string& name, long fallback, long low, long high) {
  const std::optional<double> v = optional_number(args, name);
  if (!v) return fallback;
  if (*v != std::floor(*v) || *v < static_cast<double>(low) || *v > static_cast<double>(high)) {
    throw UsageError(name + " takes a whole number " + std::to_string(low) + ".." + std::to_string(high));
  }
  return static_cast<long>(*v);
}

// "[#########.........]  45 %  match 2/3" on one line of a terminal.
class ProgressBar {
 public:
  explicit ProgressBar(bool on) : on_(on) {}
  void show(double fraction, const std::string& what) {
    if (!on_) return;
    const int width = 30;
    const int filled = static_cast<int>(std::lround(fraction * width));
    std::fprintf(stderr, "\r[%s%s] %3.0f %%  %s ", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), 100 * fraction, what.c_str());
    std::fflush(stderr);
  }
  void done() {
    if (on_) std::fprintf(stderr, "\r%60s\r", "");
  }

 private:
  bool on_;
};

// Virtual seconds per wall second: "34x", or "0.25x" below 10 (the teams' processes in a slow machine).
std::string factor(double virtual_s, double wall_s) {
  const double f = wall_s > 0 ? virtual_s / wall_s : 0.0;
  char text[32];
  std::snprintf(text, sizeof text, f >= 10 ? "%.0fx" : "%.2gx", f);
  return text;
}

double share(double mine, double theirs) { return mine + theirs > 0 ? 100 * mine / (mine + theirs) : 0; }

void print_table(const std::vector<std::string>& names, const std::vector<emulator::TeamTally>& t) {
  std::printf("  %-16s %5s %11s %6s %6s %7s %15s\n", "team", "goals", "possession", "shots", "kicks", "faults",
              "FTT violations");
  for (std::size_t k = 0; k < t.size(); ++k) {
    std::printf("  %-16s %5d %9.0f %% %6d %6d %7llu %15llu\n", names[k].c_str(), t[k].goals,
                share(t[k].possession_s, t[1 - k].possession_s), t[k].shots, t[k].kicks,
                static_cast<unsigned long long>(t[k].faults), static_cast<unsigned long long>(t[k].ftt_violations));
  }
}

// ODE's reports (physics/solver_health.hpp): the counts and the first few.
nlohmann::json solver_json(const physics::SolverHealth& h) {
  nlohmann::json first = nlohmann::json::array();
  for (const physics::SolverReport& r : h.first) {
    first.push_back(
        {{"kind", physics::solver_report_kind_name(r.kind)}, {"code", r.code}, {"time_s", r.time_s}, {"text", r.text}});
  }
  return {{"messages", h.messages}, {"internal_errors", h.internal_errors}, {"errors", h.errors}, {"first", first}};
}

nlohmann::json tally_json(const emulator::TeamTally& t, const emulator::TeamTally& other, const std::string& name) {
  return {{"team", name},
          {"goals", t.goals},
          {"possession_s", t.possession_s},
          {"possession_pct", share(t.possession_s, other.possession_s)},
          {"shots", t.shots},
          {"kicks", t.kicks},
          {"faults", t.faults},
          {"ftt_violations", t.ftt_violations}};
}

}  // namespace

int run_match(Args& args, const std::optional<std::string>& dbc) {
  const auto config = args.option("--config");
  const long halves = whole(args, "--halves", 2, 1, 4);
  const std::optional<double> half_minutes = optional_number(args, "--half-minutes");
  const long repeat = whole(args, "--repeat", 1, 1, 10'000);
  const bool json = args.flag("--json");
  const bool quiet = args.flag("--quiet");
  const std::optional<std::uint64_t> seed = seed_option(args);
  const bool external = args.flag("--external");
  std::vector<std::string> processes;
  while (auto p = args.option("--process")) processes.push_back(*p);
  const auto logs = args.option("--logs");
  const std::optional<double> answer_limit = optional_number(args, "--answer-limit");
  const auto positional = args.positionals();
  if (positional.size() > 2 || (positional.size() == 2 && config)) {
    throw UsageError("match takes one scenario (SCENARIO or --config SCENARIO)");
  }
  std::string path;
  if (positional.size() == 2) path = positional[1];
  if (config) path = *config;
  if (path.empty()) throw UsageError("match needs a scenario with two teams, e.g. emulator/scenarios/two_teams.toml");
  if (half_minutes && !(*half_minutes > 0 && *half_minutes <= 60)) throw UsageError("--half-minutes takes 0..60 min");
  emulator::Scenario scenario = [&] {
    try {
      return emulator::load_scenario(path);
    } catch (const SetupError& e) {
      throw UsageError(path + ": " + e.what());
    }
  }();
  if (!external && (!processes.empty() || logs || answer_limit)) {
    throw UsageError("--process, --logs and --answer-limit are for matches with --external");
  }
  try {
    emulator::apply_external_overrides(scenario, processes, answer_limit);
  } catch (const emulator::OverrideError& e) {
    throw UsageError(e.what());
  }
  if (external) {
    bool any = false;
    for (std::size_t t = 0; t < scenario.teams.size(); ++t) any |= !scenario.external_of(t).processes.empty();
    if (!any) {
      throw UsageError(path +
                       ": --external starts each robot's processes from its team's [teams.external] (else "
                       "[external]) processes = [...] lines, and this scenario gives none; add them, or give "
                       "--process \"COMMAND\" for both teams (docs/teams.md)");
    }
    try {
      require_told_goal(scenario, halves > 1, stderr);
    } catch (const SetupError& e) {  // the scenario to mend, not the command line: no usage
      throw SetupError(path + ": " + e.what());
    }
  }
  emulator::MatchOptions match;
  match.halves = static_cast<int>(halves);
  match.half_s = 60 * half_minutes.value_or(10);
  emulator::SessionOptions options;
  options.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  if (std::getenv("RTDB_KEY") == nullptr) {  // keys of this process, never a live robot's database
    setenv("RTDB_KEY", std::to_string(0x58000000 + ((getpid() & 0xFFFF) << 8)).c_str(), 1);
  }
  int match_number = 0;
  if (external) {
    // Before anything is printed: canhil may start itself again, with the shim preloaded.
    ExternalMatch how;
    how.shim = find_timeshim();
    how.team_preload = preload_shim_into_self(how.shim);
    how.logs = logs;
    how.match = &match_number;
    options.external = true;
    match.driver = external_halves(how);
  }
  std::signal(SIGINT, stop_match);
  std::signal(SIGTERM, stop_match);
  const std::vector<std::string> names = {scenario.teams.at(0).name,
                                          scenario.teams.size() > 1 ? scenario.teams[1].name : std::string()};
  const std::uint64_t first_seed = seed.value_or(scenario.seed);
  const double match_s = match.halves * match.half_s;
  if (!json) {
    std::printf("canhil match: %s, %ld match(es) of %d x %g min, seeds %llu..%llu, %s against %s\n", path.c_str(),
                repeat, match.halves, match.half_s / 60, static_cast<unsigned long long>(first_seed),
                static_cast<unsigned long long>(first_seed + static_cast<std::uint64_t>(repeat) - 1), names[0].c_str(),
                names[1].c_str());
    if (external) {
      // Which bus the teams' processes share with canhil's nodes (the user-space
      // bus, where the kernel has none): one line, every interface on it.
      std::string on;
      for (const std::string& iface : scenario.interfaces) on += (on.empty() ? "" : ", ") + iface;
      if (!scenario.interfaces.empty()) {
        std::printf("  the teams' processes on %s (%s)\n", on.c_str(), can_nodes::bus_of(scenario.interfaces[0]));
      }
    }
    if (!scenario.vision.any_noise()) {
      std::printf(
          "  note: the scenario's camera is exact (its [vision] gives no noise), so every seed plays the same "
          "match; docs/teams.md\n");
    }
    std::fflush(stdout);
  }
  // Not between the lines of the teams' processes (their output is on stderr unless --logs).
  ProgressBar bar(!quiet && isatty(STDERR_FILENO) != 0 && !(external && !logs));
  std::vector<emulator::TeamTally> total(2);
  physics::SolverHealth solver_total;
  std::vector<int> wins(3, 0);  // team 0, team 1, draws
  nlohmann::json matches = nlohmann::json::array();
  double wall = 0, simulated = 0;
  long played = 0;
  bool stuck = false;  // a process stopped answering: the match in progress is dropped
  for (long k = 0; k < repeat && !g_stop_match; ++k) {
    scenario.seed = first_seed + static_cast<std::uint64_t>(k);
    match_number = static_cast<int>(k + 1);
    const std::string what = "match " + std::to_string(k + 1) + "/" + std::to_string(repeat);
    emulator::MatchResult r;
    try {
      r = emulator::play_match(
          scenario, options, match,
          [&](double s) {
            bar.show((static_cast<double>(k) * match_s + s) / (static_cast<double>(repeat) * match_s), what);
          },
          &g_stop_match);
    } catch (const SetupError& e) {
      bar.done();
      throw UsageError(path + ": " + e.what());
    } catch (const emulator::ProcessStuck& e) {
      // The matches played so far are still reported; this one is not.
      bar.done();
      std::fprintf(stderr, "canhil match: stopped: %s\n", e.what());
      stuck = true;
      break;
    }
    bar.done();
    ++played;
    wall += r.wall_s;
    simulated += r.virtual_s;
    for (std::size_t t = 0; t < 2; ++t) total[t] += r.teams[t];
    solver_total.add(r.solver);
    const auto winner = r.winner();
    ++wins[winner ? *winner : 2];
    if (json) {
      nlohmann::json goals = nlohmann::json::array();
      for (const auto& g : r.goals)
        goals.push_back({{"half", g.half + 1}, {"time_s", g.time_s}, {"team", names[g.team]}});
      matches.push_back(
          {{"seed", r.seed},
           {"teams", {tally_json(r.teams[0], r.teams[1], names[0]), tally_json(r.teams[1], r.teams[0], names[1])}},
           {"goals", goals},
           {"referee_calls", r.referee_calls},
           {"solver", solver_json(r.solver)},
           {"winner", winner ? nlohmann::json(names[*winner]) : nlohmann::json(nullptr)},
           {"virtual_s", r.virtual_s},
           {"wall_s", r.wall_s},
           {"stopped", r.stopped}});
      continue;
    }
    std::printf("match %ld (seed %llu): %s %d : %d %s%s, %zu referee call(s), %.0f s in %.1f s of wall time (%s)\n",
                k + 1, static_cast<unsigned long long>(r.seed), names[0].c_str(), r.teams[0].goals, r.teams[1].goals,
                names[1].c_str(), r.stopped ? " (stopped)" : "", r.referee_calls, r.virtual_s, r.wall_s,
                factor(r.virtual_s, r.wall_s).c_str());
    for (const auto& g : r.goals) {
      std::printf("  goal  half %d  %6.1f s  %s\n", g.half + 1, g.time_s, names[g.team].c_str());
    }
    print_table(names, r.teams);
    if (r.solver.total() > 0) std::printf("  physics: %s\n", r.solver.summary().c_str());
    std::fflush(stdout);
  }
  if (json) {
    nlohmann::json out{
        {"scenario", path},
        {"halves", match.halves},
        {"half_s", match.half_s},
        {"matches", matches},
        {"total",
         {{"teams", {tally_json(total[0], total[1], names[0]), tally_json(total[1], total[0], names[1])}},
          {"wins", {{names[0], wins[0]}, {names[1], wins[1]}}},
          {"draws", wins[2]},
          {"solver", solver_json(solver_total)}}},
        {"virtual_s", simulated},
        {"wall_s", wall},
        {"stopped", g_stop_match.load() || stuck}};
    std::printf("%s\n", out.dump(2).c_str());
  } else if (played > 1) {
    std::printf("over %ld matches: %s won %d, %s won %d, %d draw(s); %.0f s of play in %.1f s (%s)\n", played,
                names[0].c_str(), wins[0], names[1].c_str(), wins[1], wins[2], simulated, wall,
                factor(simulated, wall).c_str());
    print_table(names, total);
  }
  if (!json && played > 0) std::printf("physics: %s over the match(es)\n", solver_total.summary().c_str());
  if (stuck) return kProcessStuckStatus;
  return g_stop_match ? 130 : 0;
}

}  // namespace canhil::app
