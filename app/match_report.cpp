#include "match_report.hpp"

#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/match_stats.hpp"
#include "canhil/physics/svg_plot.hpp"
#include "match_records.hpp"

namespace canhil::app {
namespace {

struct Loaded {
  nlohmann::json record;
  std::string where;  // FILE:LINE
};

// What every record of one report shares, and the first record that said it.
const char* const kShared[] = {"scenario_hash", "dbc_hash", "halves", "half_s"};

std::vector<Loaded> load(const std::vector<std::string>& files) {
  std::vector<Loaded> out;
  std::map<std::uint64_t, std::string> seen;  // seed -> where
  for (const std::string& file : files) {
    std::ifstream in(file);
    if (!in) throw SetupError(file + ": cannot read it");
    int n = 0;
    for (std::string line; std::getline(in, line);) {
      ++n;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      const std::string where = file + ":" + std::to_string(n);
      Loaded l{{}, where};
      try {
        l.record = nlohmann::json::parse(line);
        for (const char* key : {"seed", "scenario", "scenario_hash", "dbc_hash", "halves", "half_s", "failed"})
          (void)l.record.at(key);
        if (l.record.at("failed").is_null()) (void)result_of(l.record);
      } catch (const std::exception& e) {
        throw SetupError(where + ": not a match record (canhil match --records writes them): " + e.what());
      }
      const auto seed = l.record.at("seed").get<std::uint64_t>();
      if (const auto it = seen.find(seed); it != seen.end()) {
        throw SetupError(where + ": seed " + std::to_string(seed) + " again (first at " + it->second +
                         "): each match once; leave one of the two out");
      }
      seen[seed] = where;
      if (!out.empty()) {
        const nlohmann::json& first = out.front().record;
        for (const char* key : kShared) {
          if (l.record.at(key) != first.at(key)) {
            throw SetupError(where + ": " + key + " " + l.record.at(key).dump() + " is not " + first.at(key).dump() +
                             " of " + out.front().where + " (scenario " + first.at("scenario").get<std::string>() +
                             "): a report merges the matches of one scenario, DBC and match length");
          }
        }
      }
      out.push_back(std::move(l));
    }
  }
  if (out.empty()) throw SetupError("no match records in " + std::to_string(files.size()) + " file(s)");
  return out;
}

std::vector<std::string> team_names(const std::vector<Loaded>& records) {
  for (const Loaded& l : records) {
    if (l.record.contains("teams")) {
      return {l.record["teams"][0]["team"].get<std::string>(), l.record["teams"][1]["team"].get<std::string>()};
    }
  }
  return {"first", "second"};
}

std::string pct(double v) {
  char b[16];
  std::snprintf(b, sizeof b, "%.0f %%", 100 * v);
  return b;
}

}  // namespace

int run_match_report(const std::vector<std::string>& files, bool json, const std::optional<std::string>& svg) {
  const std::vector<Loaded> records = load(files);
  std::vector<emulator::MatchSummary> summaries;
  summaries.reserve(records.size());
  for (const Loaded& l : records) summaries.push_back(summary_of(l.record));
  const emulator::MatchStats s = emulator::match_stats(summaries);
  const std::vector<std::string> names = team_names(records);
  const nlohmann::json& first = records.front().record;
  const char* const rows[] = {"goals", "possession %", "shots", "kicks", "faults", "FTT violations"};
  auto figure = [&](std::size_t t, int row) {
    const emulator::TeamFigures& f = s.teams[t];
    const double v[] = {f.goals, f.possession_pct, f.shots, f.kicks, f.faults, f.ftt_violations};
    return v[row];
  };
  if (json) {
    nlohmann::json per_team = nlohmann::json::object();
    for (std::size_t t = 0; t < 2; ++t) {
      const emulator::TeamFigures& f = s.teams[t];
      per_team[names[t]] = {{"goals", f.goals},   {"possession_pct", f.possession_pct},
                            {"shots", f.shots},   {"kicks", f.kicks},
                            {"faults", f.faults}, {"ftt_violations", f.ftt_violations}};
    }
    const nlohmann::json out{
        {"scenario", first.at("scenario")},
        {"scenario_hash", first.at("scenario_hash")},
        {"dbc_hash", first.at("dbc_hash")},
        {"halves", first.at("halves")},
        {"half_s", first.at("half_s")},
        {"teams", names},
        {"matches", s.matches},
        {"failed", s.crashed},
        {"wins", s.wins},
        {"draws", s.draws},
        {"losses", s.losses},
        {"goal_difference",
         {{"mean", s.goal_difference},
          {"sd", s.goal_difference_sd},
          {"ci95", {s.goal_difference_ci.low, s.goal_difference_ci.high}}}},
        {"win_rate", {{"value", s.win_rate}, {"wilson95", {s.win_rate_ci.low, s.win_rate_ci.high}}}},
        {"sign_test_p", s.sign_p},
        {"significant", s.significant},
        {"per_match", per_team},
        {"solver_messages", s.solver_messages},
        {"virtual_s", s.virtual_s},
        {"wall_s", s.wall_s}};
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    std::printf("canhil match --report: %d match(es) of %s (%d x %g min) from %zu file(s)%s\n", s.matches,
                first.at("scenario").get<std::string>().c_str(), first.at("halves").get<int>(),
                first.at("half_s").get<double>() / 60, files.size(),
                s.crashed > 0 ? (", " + std::to_string(s.crashed) + " failed (not counted)").c_str() : "");
    std::printf("  %s against %s: %d won, %d drawn, %d lost\n", names[0].c_str(), names[1].c_str(), s.wins, s.draws,
                s.losses);
    std::printf("  goal difference (%s - %s): %+.2f per match, 95 %% interval %+.2f .. %+.2f\n", names[0].c_str(),
                names[1].c_str(), s.goal_difference, s.goal_difference_ci.low, s.goal_difference_ci.high);
    std::printf("  win rate of %s: %s (Wilson 95 %%: %s .. %s)\n", names[0].c_str(), pct(s.win_rate).c_str(),
                pct(s.win_rate_ci.low).c_str(), pct(s.win_rate_ci.high).c_str());
    std::printf("  the teams %s at 5 %% (sign test on the %d decided matches: p = %.3g)\n",
                s.significant ? "DIFFER significantly" : "do not differ significantly", s.wins + s.losses, s.sign_p);
    std::printf("  %-16s %10s %10s   (per match)\n", "", names[0].c_str(), names[1].c_str());
    for (int row = 0; row < 6; ++row) std::printf("  %-16s %10.2f %10.2f\n", rows[row], figure(0, row), figure(1, row));
    std::printf("  physics: %llu solver message(s); %.0f s of play in %.1f s of wall time\n",
                static_cast<unsigned long long>(s.solver_messages), s.virtual_s, s.wall_s);
  }
  if (svg) {
    physics::Plot histogram{
        "Goal difference per match (" + names[0] + " - " + names[1] + ")", "goal difference", "matches", {}};
    // Bars as outlines, one a goal wide, every difference from the least to the most (none: a gap).
    physics::Series h{"matches", {}, {}};
    if (!s.goal_difference_histogram.empty()) {
      const int least = s.goal_difference_histogram.begin()->first;
      const int most = s.goal_difference_histogram.rbegin()->first;
      for (int d = least; d <= most; ++d) {
        const auto it = s.goal_difference_histogram.find(d);
        const double n = it == s.goal_difference_histogram.end() ? 0 : it->second;
        for (const auto& [x, y] : {std::pair{d - 0.45, 0.0}, {d - 0.45, n}, {d + 0.45, n}, {d + 0.45, 0.0}}) {
          h.x.push_back(x);
          h.y.push_back(y);
        }
      }
    }
    histogram.series.push_back(h);
    physics::Plot rate{"Win rate of " + names[0] + " as the matches accumulate, with its Wilson 95 % interval",
                       "matches",
                       "win rate",
                       {}};
    physics::Series value{"win rate", {}, {}}, low{"interval, low", {}, {}}, high{"interval, high", {}, {}};
    for (std::size_t k = 0; k < s.running_win_rate.size(); ++k) {
      const auto x = static_cast<double>(k + 1);
      value.x.push_back(x);
      value.y.push_back(s.running_win_rate[k]);
      low.x.push_back(x);
      low.y.push_back(s.running_ci[k].low);
      high.x.push_back(x);
      high.y.push_back(s.running_ci[k].high);
    }
    rate.series = {value, low, high};
    std::ofstream out(*svg);
    out << physics::svg_plots({histogram, rate});
    if (!out) throw SetupError("cannot write " + *svg);
  }
  return 0;
}

}  // namespace canhil::app
