#include "match_records.hpp"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

#include "canhil/base/setup_error.hpp"

namespace canhil::app {
namespace {

std::string hex(std::uint64_t v) {
  char b[20];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

nlohmann::json team_json(const emulator::TeamTally& t, const emulator::TeamTally& other, const std::string& name) {
  const double both = t.possession_s + other.possession_s;
  return {{"team", name},
          {"goals", t.goals},
          {"possession_s", t.possession_s},
          {"possession_pct", both > 0 ? 100 * t.possession_s / both : 0.0},
          {"shots", t.shots},
          {"kicks", t.kicks},
          {"faults", t.faults},
          {"ftt_violations", t.ftt_violations}};
}

nlohmann::json base(std::uint64_t seed, const RecordContext& c) {
  nlohmann::json r{{"seed", seed},           {"scenario", c.scenario}, {"scenario_hash", c.scenario_hash},
                   {"dbc_hash", c.dbc_hash}, {"canhil", c.version},    {"halves", c.halves},
                   {"half_s", c.half_s}};
  if (!c.processes.empty()) r["processes"] = c.processes;
  return r;
}

}  // namespace

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SetupError("cannot read " + path + " to hash it");
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it) {
    h ^= static_cast<std::uint8_t>(*it);
    h *= 0x100000001b3ULL;
  }
  return hex(h);
}

nlohmann::json match_record(const emulator::MatchResult& r, const RecordContext& c) {
  nlohmann::json out = base(r.seed, c);
  nlohmann::json goals = nlohmann::json::array();
  for (const auto& g : r.goals)
    goals.push_back({{"half", g.half + 1}, {"time_s", g.time_s}, {"team", c.teams.at(g.team)}});
  const auto winner = r.winner();
  out["teams"] = {team_json(r.teams[0], r.teams[1], c.teams.at(0)), team_json(r.teams[1], r.teams[0], c.teams.at(1))};
  out["score"] = std::to_string(r.teams[0].goals) + ":" + std::to_string(r.teams[1].goals);
  out["winner"] = winner ? nlohmann::json(c.teams.at(*winner)) : nlohmann::json(nullptr);
  out["goals"] = goals;
  out["referee_calls"] = r.referee_calls;
  nlohmann::json calls = nlohmann::json::array();
  for (const emulator::MatchCall& x : r.calls) {
    calls.push_back({{"half", x.half + 1},
                     {"time_s", x.time_s},
                     {"restart", x.restart},
                     {"team", x.team ? nlohmann::json(c.teams.at(*x.team)) : nlohmann::json(nullptr)},
                     {"text", x.text}});
  }
  out["referee"] = calls;
  nlohmann::json first = nlohmann::json::array();
  for (const physics::SolverReport& x : r.solver.first) {
    first.push_back(
        {{"kind", physics::solver_report_kind_name(x.kind)}, {"code", x.code}, {"time_s", x.time_s}, {"text", x.text}});
  }
  out["solver"] = {{"messages", r.solver.messages},
                   {"internal_errors", r.solver.internal_errors},
                   {"errors", r.solver.errors},
                   {"first", first}};
  out["virtual_s"] = r.virtual_s;
  out["wall_s"] = r.wall_s;
  out["trace_hash"] = hex(r.trace_hash);
  out["stopped"] = r.stopped;
  out["failed"] = nullptr;
  return out;
}

nlohmann::json failed_record(std::uint64_t seed, const std::string& why, const RecordContext& c) {
  nlohmann::json out = base(seed, c);
  out["failed"] = why;
  return out;
}

emulator::MatchResult result_of(const nlohmann::json& j) {
  emulator::MatchResult r;
  r.seed = j.at("seed").get<std::uint64_t>();
  r.teams.resize(2);
  for (std::size_t t = 0; t < 2; ++t) {
    const nlohmann::json& x = j.at("teams").at(t);
    emulator::TeamTally& y = r.teams[t];
    y.goals = x.at("goals").get<int>();
    y.possession_s = x.at("possession_s").get<double>();
    y.shots = x.at("shots").get<int>();
    y.kicks = x.at("kicks").get<int>();
    y.faults = x.at("faults").get<std::uint64_t>();
    y.ftt_violations = x.at("ftt_violations").get<std::uint64_t>();
  }
  for (const nlohmann::json& g : j.at("goals")) {
    const std::size_t team =
        g.at("team").get<std::string>() == j.at("teams").at(0).at("team").get<std::string>() ? 0 : 1;
    r.goals.push_back({g.at("half").get<int>() - 1, g.at("time_s").get<double>(), team});
  }
  r.referee_calls = j.at("referee_calls").get<std::size_t>();
  for (const nlohmann::json& x : j.value("referee", nlohmann::json::array())) {  // records before 2026-11-28 have none
    std::optional<std::size_t> team;
    if (!x.at("team").is_null())
      team = x.at("team").get<std::string>() == j.at("teams").at(0).at("team").get<std::string>() ? 0 : 1;
    r.calls.push_back({x.at("half").get<int>() - 1, x.at("time_s").get<double>(), x.at("restart").get<std::string>(),
                       team, x.at("text").get<std::string>()});
  }
  r.solver.messages = j.at("solver").at("messages").get<std::uint64_t>();
  r.solver.internal_errors = j.at("solver").at("internal_errors").get<std::uint64_t>();
  r.solver.errors = j.at("solver").at("errors").get<std::uint64_t>();
  for (const nlohmann::json& x : j.at("solver").value("first", nlohmann::json::array())) {
    physics::SolverReport report;
    const std::string kind = x.at("kind").get<std::string>();
    for (const auto k : {physics::SolverReportKind::kMessage, physics::SolverReportKind::kInternalError,
                         physics::SolverReportKind::kError}) {
      if (kind == physics::solver_report_kind_name(k)) report.kind = k;
    }
    report.code = x.at("code").get<int>();
    report.time_s = x.at("time_s").get<double>();
    report.text = x.at("text").get<std::string>();
    r.solver.first.push_back(report);
  }
  r.virtual_s = j.at("virtual_s").get<double>();
  r.wall_s = j.at("wall_s").get<double>();
  r.trace_hash = std::stoull(j.at("trace_hash").get<std::string>(), nullptr, 16);
  r.stopped = j.at("stopped").get<bool>();
  return r;
}

emulator::MatchSummary summary_of(const nlohmann::json& j) {
  emulator::MatchSummary m;
  m.seed = j.at("seed").get<std::uint64_t>();
  if (!j.at("failed").is_null()) {
    m.crashed = true;
    return m;
  }
  const emulator::MatchResult r = result_of(j);
  for (std::size_t t = 0; t < 2; ++t) {
    m.goals[t] = r.teams[t].goals;
    m.possession_s[t] = r.teams[t].possession_s;
    m.shots[t] = r.teams[t].shots;
    m.kicks[t] = r.teams[t].kicks;
    m.faults[t] = r.teams[t].faults;
    m.ftt_violations[t] = r.teams[t].ftt_violations;
  }
  m.solver_messages = r.solver.messages;
  m.virtual_s = r.virtual_s;
  m.wall_s = r.wall_s;
  return m;
}

std::vector<std::uint64_t> parse_seeds(const std::string& text) {
  constexpr std::uint64_t kMost = 1'000'000;
  std::vector<std::uint64_t> out;
  std::istringstream in(text);
  auto number = [&](const std::string& s) -> std::uint64_t {
    std::size_t used = 0;
    if (s.empty() || s[0] < '0' || s[0] > '9') throw std::invalid_argument(s);
    const unsigned long long v = std::stoull(s, &used);
    if (used != s.size()) throw std::invalid_argument(s);
    return v;
  };
  try {
    for (std::string part; std::getline(in, part, ',');) {
      const auto dots = part.find("..");
      const std::uint64_t first = number(part.substr(0, dots));
      const std::uint64_t last = dots == std::string::npos ? first : number(part.substr(dots + 2));
      if (last < first || last - first >= kMost || out.size() + (last - first + 1) > kMost)
        throw std::invalid_argument(part);
      for (std::uint64_t s = first; s <= last; ++s) out.push_back(s);
    }
  } catch (const std::exception&) {
    throw std::invalid_argument(
        "--seeds takes seeds and ranges, comma-separated (1..200, 7, 1,5,9, 1..10,20..30; at most " +
        std::to_string(kMost) + "), got \"" + text + "\"");
  }
  if (out.empty()) throw std::invalid_argument("--seeds: no seed in \"" + text + "\"");
  return out;
}

}  // namespace canhil::app
