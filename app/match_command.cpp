// `canhil match SCENARIO [--halves 2] [--half-minutes 10] [--repeat N]
// [--seed S] [--json] [--quiet] [--logs DIR] [--external [--process CMD]...
// [--answer-limit S]]`: whole matches of a two-team scenario in virtual time
// (emulator/match.hpp), one seed per match (S, S+1, ...), and a table per
// match and over all of them: score, possession, shots, kicks, faults and FTT
// violations per team. A progress bar on a terminal's stderr. With
// --external the teams' own processes play (canhil/external/external_half.hpp).
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/external_driver.hpp"
#include "canhil/emulator/match.hpp"
#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/external/external_half.hpp"
#include "canhil/external/external_run.hpp"
#include "canhil/external/match_workers.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/external/team_processes.hpp"
#include "canhil/external/time_shim.hpp"
#include "canhil/external/worker.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"
#include "log_file.hpp"
#include "match_records.hpp"
#include "match_report.hpp"
#include "run_external.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

// Whole numbers only, in a range.
long whole(Args& args, const std::string& name, long fallback, long low, long high) {
  const std::optional<double> v = optional_number(args, name);
  if (!v) return fallback;
  if (*v != std::floor(*v) || *v < static_cast<double>(low) || *v > static_cast<double>(high)) {
    throw UsageError(name + " takes a whole number " + std::to_string(low) + ".." + std::to_string(high));
  }
  return static_cast<long>(*v);
}

// Progress of a batch on stderr. On a terminal one line, redrawn: a bar,
// matches done, the running score and an estimate of the time left; else a
// plain line per match. Off with --quiet.
class Progress {
 public:
  Progress(bool on, bool terminal, std::size_t matches, double match_s, std::vector<std::string> names)
      : on_(on),
        terminal_(terminal),
        matches_(matches),
        match_s_(match_s),
        names_(std::move(names)),
        start_(std::chrono::steady_clock::now()) {}
  /// A match under way has played `played_s` (virtual).
  void update(std::uint64_t seed, double played_s) {
    playing_[seed] = played_s;
    draw();
  }
  /// A match ended: 0 or 1 its winner, 2 a draw, none a failure.
  void finished(std::optional<int> outcome) {
    ++done_;
    if (outcome) ++score_[static_cast<std::size_t>(*outcome)];
    playing_.clear();
    if (on_ && !terminal_ && matches_ > 1) {
      std::fprintf(stderr, "canhil match: %zu/%zu done, %s\n", done_, matches_, status().c_str());
    } else {
      draw();
    }
  }
  void clear() {
    if (on_ && terminal_ && drawn_) std::fprintf(stderr, "\r%100s\r", "");
    drawn_ = false;
  }

 private:
  // Matches done, and the part played of those under way.
  double matches_played() const {
    double played = static_cast<double>(done_);
    for (const auto& [seed, s] : playing_) played += std::min(1.0, s / match_s_);
    return played;
  }
  std::string status() const {
    char b[200];
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double progress = matches_played();
    std::string left = "?";
    if (progress > 0.05) {
      const double seconds = elapsed / progress * (static_cast<double>(matches_) - progress);
      char t[32];
      std::snprintf(t, sizeof t, seconds >= 90 ? "%.0f min" : "%.0f s", seconds >= 90 ? seconds / 60 : seconds);
      left = t;
    }
    std::snprintf(b, sizeof b, "%s %d, %s %d, %d draw(s); about %s left", names_[0].c_str(), score_[0],
                  names_[1].c_str(), score_[1], score_[2], left.c_str());
    return b;
  }
  void draw() {
    if (!on_ || !terminal_) return;
    const double progress = matches_played();
    const double fraction = progress / static_cast<double>(matches_);
    const int width = 24;
    const int filled = static_cast<int>(std::lround(fraction * width));
    std::fprintf(stderr, "\r[%s%s] %zu/%zu  %s ", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), done_, matches_, status().c_str());
    std::fflush(stderr);
    drawn_ = true;
  }

  bool on_, terminal_;
  std::size_t matches_;
  double match_s_;
  std::vector<std::string> names_;
  std::chrono::steady_clock::time_point start_;
  std::size_t done_ = 0;
  std::array<int, 3> score_{};
  std::map<std::uint64_t, double> playing_;
  bool drawn_ = false;
};

// "5..24", "1, 3, 7", "1..10, 20": the seeds as given, ranges folded.
std::string seed_list(const std::vector<std::uint64_t>& seeds) {
  std::string out;
  for (std::size_t i = 0; i < seeds.size();) {
    std::size_t j = i;
    while (j + 1 < seeds.size() && seeds[j + 1] == seeds[j] + 1) ++j;
    out += (out.empty() ? "" : ", ") + std::to_string(seeds[i]) + (j > i ? ".." + std::to_string(seeds[j]) : "");
    i = j + 1;
  }
  return out;
}

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
  const bool json = args.flag("--json");
  if (args.flag("--report")) {
    const auto svg = args.option("--svg");
    std::vector<std::string> files = args.positionals();
    files.erase(files.begin());
    if (files.empty()) throw UsageError("match --report takes the record files to merge (RECORDS.jsonl...)");
    return run_match_report(files, json, svg);
  }
  const auto config = args.option("--config");
  const long halves = whole(args, "--halves", 2, 1, 4);
  const std::optional<double> half_minutes = optional_number(args, "--half-minutes");
  const bool repeat_given = args.given("--repeat");
  const long repeat = whole(args, "--repeat", 1, 1, 10'000);
  const auto seeds_text = args.option("--seeds");
  const long cores = std::max(1L, static_cast<long>(std::thread::hardware_concurrency()));
  const bool jobs_given = args.given("--jobs");
  const long jobs = whole(args, "--jobs", cores, 1, 256);
  const auto records_option = args.option("--records");
  const bool no_records = args.flag("--no-records");
  const bool quiet = args.flag("--quiet");
  const std::optional<std::uint64_t> seed = seed_option(args);
  const bool external = args.flag("--external");
  std::vector<std::string> processes;
  while (auto p = args.option("--process")) processes.push_back(*p);
  const auto logs = args.option("--logs");
  const std::optional<double> answer_limit = optional_number(args, "--answer-limit");
  const std::optional<double> bit_rate = optional_number(args, "--bit-rate");
  const auto positional = args.positionals();
  if (positional.size() > 2 || (positional.size() == 2 && config)) {
    throw UsageError("match takes one scenario (SCENARIO or --config SCENARIO)");
  }
  if (seeds_text && (seed || repeat_given)) throw UsageError("--seeds names every seed: leave --seed and --repeat out");
  if (records_option && no_records) throw UsageError("--records FILE or --no-records, not both");
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
  if (!external && (!processes.empty() || answer_limit)) {
    throw UsageError("--process and --answer-limit are for matches with --external");
  }
  emulator::RunOverrides over;  // what the command line says over the file, for every half
  over.processes = processes;
  over.answer_limit_s = answer_limit;
  over.bit_rate = bit_rate;
  // What each half's plan will start: the file's [external] sides with the command line's over them.
  const emulator::Scenario planned = [&] {
    try {
      return emulator::overridden(scenario, over);
    } catch (const emulator::OverrideError& e) {
      throw UsageError(e.what());
    }
  }();
  if (external) {
    bool any = false;
    for (std::size_t t = 0; t < planned.teams.size(); ++t) any |= !planned.external_of(t).processes.empty();
    if (!any) {
      throw UsageError(path +
                       ": --external starts each robot's processes from its team's [teams.external] (else "
                       "[external]) processes = [...] lines, and this scenario gives none; add them, or give "
                       "--process \"COMMAND\" for both teams (docs/teams.md)");
    }
    try {
      external::require_told_goal(planned, halves > 1, stderr);
    } catch (const SetupError& e) {  // the scenario to mend, not the command line: no usage
      throw SetupError(path + ": " + e.what());
    }
  }
  std::vector<std::uint64_t> seeds;
  try {
    if (seeds_text) seeds = parse_seeds(*seeds_text);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  if (seeds.empty()) {
    const std::uint64_t first_seed = seed.value_or(scenario.seed);
    for (long k = 0; k < repeat; ++k) seeds.push_back(first_seed + static_cast<std::uint64_t>(k));
  }
  emulator::MatchOptions match;
  match.overrides = over;
  match.halves = static_cast<int>(halves);
  match.half_s = 60 * half_minutes.value_or(10);
  emulator::SessionOptions options;
  options.messages = frames::MessageSet::create(load_chosen_dbc(dbc));
  external::use_private_rtdb_keys(external::kRunKeyPrefix);  // keys of this process, never a live robot's database
  if (logs) {
    // Every half's trace and world log, to look at with `canhil view` (docs/teams.md).
    std::error_code made;
    std::filesystem::create_directories(*logs, made);
    match.keep_logs = true;
    match.half_ended = [dir = *logs](const emulator::Session& session, const emulator::HalfDriver& driver,
                                     std::uint64_t match_seed, int half) {
      const std::string name = dir + "/seed" + std::to_string(match_seed) + "-half" + std::to_string(half + 1);
      write_file(name + ".log", driver.trace(), "half's trace");
      write_file(name + ".csv", session.world_log(), "half's world log");
    };
  }
  int match_number = 0;
  // With the teams' processes, one match at a time unless --jobs says more:
  // each worker then has its own bus and IPC namespace (canhil/external/worker.hpp).
  const long workers =
      std::min<long>(external && !jobs_given ? 1 : jobs, static_cast<long>(std::max<std::size_t>(1, seeds.size())));
  if (external) {
    // Before anything is printed: canhil may start itself again, with the shim preloaded.
    if (workers > 1) external::prepare_external_workers();
    external::ExternalMatch how;
    how.shim = external::find_timeshim();
    how.team_preload = external::preload_shim_into_self(how.shim);
    how.logs = logs;
    how.match = &match_number;
    how.alone = workers == 1;
    options.external = true;
    match.driver = external::external_halves(how);
  }
  stop_on_signals();
  const std::vector<std::string> names = {scenario.teams.at(0).name,
                                          scenario.teams.size() > 1 ? scenario.teams[1].name : std::string()};
  RecordContext context;
  context.scenario = path;
  context.scenario_hash = file_hash(path);
  context.dbc_hash = file_hash(dbc ? *dbc : frames::default_dbc_path().string());
  context.version = CANHIL_VERSION;
  context.halves = match.halves;
  context.half_s = match.half_s;
  context.teams = names;
  if (external) {
    for (std::size_t t = 0; t < 2 && t < scenario.teams.size(); ++t)
      context.processes.push_back(planned.external_of(t).processes);
  }
  const std::string records_path =
      no_records ? std::string()
                 : records_option.value_or((logs ? *logs + "/" : std::string()) + "match-records.jsonl");
  // Opened at the first record (a batch that never plays leaves nothing behind), checked now.
  std::ofstream records;
  if (!records_path.empty()) {
    const std::filesystem::path where(records_path);
    const std::filesystem::path dir = where.has_parent_path() ? where.parent_path() : std::filesystem::path(".");
    std::error_code made;
    std::filesystem::create_directories(dir, made);  // --logs DIR's, made now rather than at the first half
    if (::access(std::filesystem::exists(where) ? records_path.c_str() : dir.c_str(), W_OK) != 0) {
      throw SetupError("cannot write the match records to " + records_path + " (--records FILE, or --no-records)");
    }
  }
  const auto write_record = [&](const nlohmann::json& r) {
    if (records_path.empty()) return;
    if (!records.is_open()) records.open(records_path, std::ios::app);
    records << r.dump() << '\n' << std::flush;
  };
  const double match_s = match.halves * match.half_s;
  if (!json) {
    std::printf("canhil match: %s, %zu match(es) of %d x %g min, seeds %s, %s against %s%s\n", path.c_str(),
                seeds.size(), match.halves, match.half_s / 60, seed_list(seeds).c_str(), names[0].c_str(),
                names[1].c_str(), workers > 1 ? (", " + std::to_string(workers) + " at a time").c_str() : "");
    if (external) {
      // Which bus the teams' processes share with canhil's nodes (the user-space
      // bus, where the kernel has none): one line, every interface on it.
      std::string on;
      for (const std::string& iface : scenario.interfaces) on += (on.empty() ? "" : ", ") + iface;
      if (workers > 1) {
        std::printf("  each match's processes on %s of a user-space bus and an IPC namespace of the match's own\n",
                    on.c_str());
      } else if (!scenario.interfaces.empty()) {
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
  Progress progress(!quiet && !(external && !logs), isatty(STDERR_FILENO) != 0, seeds.size(), match_s, names);
  std::vector<emulator::TeamTally> total(2);
  physics::SolverHealth solver_total;
  std::vector<int> wins(3, 0);  // team 0, team 1, draws
  nlohmann::json matches = nlohmann::json::array();
  double wall = 0, simulated = 0;
  long played = 0;
  long failed = 0;
  bool stuck = false;  // a process stopped answering: the match in progress is dropped
  // Each record in the order of the seeds: into the file, the tally and the output.
  const auto done = [&](const nlohmann::json& record) {
    write_record(record);
    const auto k = static_cast<long>(played + failed);
    if (!record.at("failed").is_null()) {
      ++failed;
      progress.finished(std::nullopt);
      if (json) {
        matches.push_back(record);
      } else {
        std::printf("match %ld (seed %llu): FAILED: %s\n", k + 1,
                    static_cast<unsigned long long>(record.at("seed").get<std::uint64_t>()),
                    record.at("failed").get<std::string>().c_str());
      }
      return;
    }
    const emulator::MatchResult r = result_of(record);
    ++played;
    wall += r.wall_s;
    simulated += r.virtual_s;
    for (std::size_t t = 0; t < 2; ++t) total[t] += r.teams[t];
    solver_total.add(r.solver);
    const auto winner = r.winner();
    ++wins[winner ? *winner : 2];
    progress.finished(winner ? std::optional<int>(static_cast<int>(*winner)) : std::optional<int>(2));
    if (json) {
      matches.push_back(record);
      return;
    }
    progress.clear();
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
  };
  const auto play = [&](int number, std::uint64_t s, const std::function<void(double)>& on_progress) {
    // A test's way to make a match's process die (docs/testing.md): a crash, reported, the batch going on.
    if (const char* die = std::getenv("CANHIL_MATCH_KILL_SEED"); die != nullptr && std::to_string(s) == die) {
      std::raise(SIGKILL);
    }
    emulator::MatchOptions this_match = match;
    this_match.overrides.seed = s;
    match_number = number;
    return match_record(emulator::play_match(scenario, options, this_match, on_progress, &g_stop), context);
  };
  if (!external || workers > 1) {
    external::MatchJobs jobs_of;
    jobs_of.play = [&](int number, std::uint64_t s, const std::function<void(double)>& on_progress) {
      return play(number, s, on_progress).dump();
    };
    if (external) {
      // A process that stops answering fails its match; the other workers go on.
      jobs_of.play = [&](int number, std::uint64_t s, const std::function<void(double)>& on_progress) {
        external::ExternalWorker::next_match();
        try {
          return play(number, s, on_progress).dump();
        } catch (const emulator::ProcessStuck& e) {
          return failed_record(s, std::string("stuck: ") + e.what(), context).dump();
        }
      };
      jobs_of.enter = [&](int) -> std::shared_ptr<void> {
        return std::make_shared<external::ExternalWorker>(scenario.interfaces);
      };
    }
    jobs_of.failed = [&](std::uint64_t s, const std::string& why) { return failed_record(s, why, context).dump(); };
    jobs_of.done = [&](const std::string& record) { done(nlohmann::json::parse(record)); };
    jobs_of.progress = [&](std::uint64_t s, double played_s) { progress.update(s, played_s); };
    std::optional<std::string> failed_setup;
    try {
      external::play_in_workers(seeds, static_cast<int>(workers), jobs_of, g_stop);
    } catch (const SetupError& e) {
      failed_setup = path + ": " + e.what();
    }
    // Each worker ended in IPC namespaces of its own, away from its claim of keys.
    if (external) external::remove_orphan_rtdb_keys(external::kRunKeyPrefix);
    if (failed_setup) {
      progress.clear();
      // A worker's own bus or namespace is the machine's matter, not the command line's.
      if (external) throw SetupError(*failed_setup);
      throw UsageError(*failed_setup);
    }
  } else {
    for (std::size_t k = 0; k < seeds.size() && !g_stop; ++k) {
      nlohmann::json record;
      try {
        record = play(static_cast<int>(k + 1), seeds[k], [&](double s) { progress.update(seeds[k], s); });
      } catch (const SetupError& e) {
        progress.clear();
        throw UsageError(path + ": " + e.what());
      } catch (const emulator::ProcessStuck& e) {
        // The matches played so far are still reported; this one is recorded as failed, and the batch stops.
        progress.clear();
        std::fprintf(stderr, "canhil match: stopped: %s\n", e.what());
        write_record(failed_record(seeds[k], std::string("stuck: ") + e.what(), context));
        stuck = true;
        break;
      }
      done(record);
    }
  }
  progress.clear();
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
          {"failed", failed},
          {"solver", solver_json(solver_total)}}},
        {"virtual_s", simulated},
        {"wall_s", wall},
        {"stopped", g_stop.load() || stuck}};
    std::printf("%s\n", out.dump(2).c_str());
  } else if (played + failed > 1) {
    std::printf("over %ld matches: %s won %d, %s won %d, %d draw(s)%s; %.0f s of play in %.1f s (%s)\n", played,
                names[0].c_str(), wins[0], names[1].c_str(), wins[1], wins[2],
                failed > 0 ? (", " + std::to_string(failed) + " failed").c_str() : "", simulated, wall,
                factor(simulated, wall).c_str());
    print_table(names, total);
  }
  if (!json && played > 0) std::printf("physics: %s over the match(es)\n", solver_total.summary().c_str());
  if (!json && !records_path.empty() && played + failed > 0) {
    std::printf("records: %s (canhil match --report %s)\n", records_path.c_str(), records_path.c_str());
  }
  if (stuck) return external::kProcessStuckStatus;
  if (g_stop) return 130;
  return failed > 0 ? 1 : 0;  // a match that failed is canhil's fault: a batch's CI must see it
}

}  // namespace canhil::app
