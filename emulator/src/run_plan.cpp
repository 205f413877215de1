#include "canhil/emulator/run_plan.hpp"

#include <algorithm>
#include <cstdio>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/emulator/laptop_link.hpp"

namespace canhil::emulator {
namespace {

// The laptop sides as the run opens them: the first team's [laptop] (and
// every team's own) resolved in place, so that whoever reads the scenario
// later sees what the run uses; per team its side, the second team's
// replicator on only when it has more than one robot and nobody said.
std::vector<LaptopSide> resolve_laptops(Scenario& s, bool realtime) {
  const std::size_t n = s.robot_count();
  for (Team& team : s.teams) {
    if (team.laptop) team.laptop = resolve_laptop(*team.laptop, team.robots, realtime);
  }
  const bool replicate_given = s.laptop.replicate.has_value();
  s.laptop = resolve_laptop(s.laptop, s.teams.size() == 1 ? n : s.teams[0].robots, realtime);
  std::vector<LaptopSide> sides;
  for (std::size_t t = 0; t < s.teams.size(); ++t) {
    const Team& team = s.teams[t];
    LaptopSide side = s.laptop_of(t);
    if (!team.laptop && t > 0 && !replicate_given) side.replicate = team.robots > 1;
    sides.push_back(std::move(side));
  }
  return sides;
}

// The longest `field` the run's external sides give.
double longest(const Scenario& s, double ExternalSide::*field) {
  double most = s.external.*field;
  if (!s.teams.empty()) most = 0;
  for (std::size_t t = 0; t < s.teams.size(); ++t) most = std::max(most, s.external_of(t).*field);
  return most;
}

ExternalPlan resolve_external(const Scenario& s) {
  ExternalPlan e;
  e.conductor.answer_limit = from_seconds(longest(s, &ExternalSide::answer_limit_s));
  e.conductor.busy_limit = from_seconds(longest(s, &ExternalSide::busy_limit_s));
  e.conductor.spin = from_seconds(longest(s, &ExternalSide::spin_us) * 1e-6);
  e.attach_limit_s = longest(s, &ExternalSide::attach_limit_s);
  e.bus_spin_us = longest(s, &ExternalSide::bus_spin_us);
  e.syslog = s.external.syslog;
  for (std::size_t r = 0; r < s.robot_count(); ++r) {
    const std::size_t team = s.team_of(r);
    const ExternalSide& side = s.external_of(team);
    for (const std::string& c : side.processes)
      e.launches.push_back({r, team, s.agents[r], expand_command(c, s, r), side.syslog});
  }
  return e;
}

}  // namespace

std::string expand_command(std::string command, const Scenario& scenario, std::size_t robot) {
  const auto replace = [&command](const std::string& key, const std::string& value) {
    for (std::size_t at = command.find(key); at != std::string::npos; at = command.find(key, at + value.size())) {
      command.replace(at, key.size(), value);
    }
  };
  const auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v + 0.0);  // + 0.0: -0 prints as 0
    return std::string(text);
  };
  const physics::Placement& at = scenario.world.robots.at(robot);
  const double goal_x = scenario.world.field.length_m / 2;
  replace("{agent}", std::to_string(scenario.agents.at(robot)));
  replace("{iface}", scenario.interfaces.at(robot));
  replace("{x}", number(at.x_m));
  replace("{y}", number(at.y_m));
  replace("{heading}", number(at.heading_deg));
  replace("{goal_x}", number(scenario.teams.at(scenario.team_of(robot)).attacks_positive_x ? goal_x : -goal_x));
  return command;
}

RunPlan plan_run(Scenario scenario, SessionOptions options) {
  if (!options.messages) throw SetupError("a run needs a message set");
  RunPlan plan;
  complete(scenario);
  if (options.vision_on) plan.laptops = resolve_laptops(scenario, options.realtime || options.external);
  plan.length = scenario.run_length(std::nullopt, options.realtime);
  if (options.external) plan.external = resolve_external(scenario);
  plan.scenario = std::move(scenario);
  plan.options = std::move(options);
  return plan;
}

void apply_external_overrides(Scenario& scenario, const std::vector<std::string>& processes,
                              const std::optional<double>& answer_limit_s) {
  if (!processes.empty()) scenario.external.processes = processes;
  if (!answer_limit_s) return;
  if (!(*answer_limit_s >= 0.01 && *answer_limit_s <= 3600)) throw OverrideError("--answer-limit takes 0.01..3600 s");
  scenario.external.answer_limit_s = *answer_limit_s;
  for (Team& team : scenario.teams) {
    if (team.external) team.external->answer_limit_s = *answer_limit_s;  // the flag is the whole run's
  }
}

RunPlan plan_run(const std::optional<std::filesystem::path>& file, const RunOverrides& o, SessionOptions options) {
  Scenario s = load_scenario(file ? *file : shipped_scenario("one_robot.toml"));
  LaptopSide& side = s.laptop;
  if (o.rtdb_lib) side.rtdb_lib = *o.rtdb_lib;
  if (o.rtdb_items) side.rtdb_items = *o.rtdb_items;
  if (o.rtdb_ini) side.rtdb_ini = *o.rtdb_ini;
  if (o.layout) side.layout = *o.layout;
  if (o.pman) side.pman = *o.pman;
  if (o.kick_power) s.kick_power = *o.kick_power;
  if (o.seed) s.seed = *o.seed;
  apply_external_overrides(s, o.processes, o.answer_limit_s);
  RunLength length;
  try {
    length = s.run_length(o.duration_s, o.mode == RunMode::kRealtime);
  } catch (const SetupError& e) {
    throw OverrideError(e.what());
  }
  for (const std::string& f : o.faults) {
    try {
      s.faults.push_back(can_nodes::parse_fault(f));
    } catch (const SetupError& e) {
      throw OverrideError(std::string("--fault: ") + e.what());
    }
  }
  options.realtime = o.mode == RunMode::kRealtime;
  options.external = o.mode == RunMode::kExternal;
  RunPlan plan;
  try {
    plan = plan_run(std::move(s), std::move(options));
  } catch (const SetupError& e) {  // a laptop side the file (or an override) leaves incomplete
    throw SetupError((file ? file->string() + ": " : std::string()) + e.what());
  }
  plan.source = file.value_or(std::filesystem::path());
  plan.length = length;
  return plan;
}

}  // namespace canhil::emulator
