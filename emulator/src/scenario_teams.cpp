// [[teams]] in a scenario, and the checks every scenario's teams pass.
#include <algorithm>
#include <cctype>
#include <set>
#include <string>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/scenario.hpp"
#include "table_reader.hpp"

namespace canhil::emulator {

std::size_t Scenario::team_of(std::size_t robot) const noexcept {
  for (std::size_t t = 0; t < teams.size(); ++t) {
    if (robot >= teams[t].first_robot && robot < teams[t].first_robot + teams[t].robots) return t;
  }
  return 0;
}

bool Scenario::mixes_real_boards() const noexcept {
  return std::any_of(emulate.begin(), emulate.end(), [](can_nodes::NodeSet e) { return !e.is_all(); });
}

const LaptopSide& Scenario::laptop_of(std::size_t team) const noexcept {
  return team < teams.size() && teams[team].laptop ? *teams[team].laptop : laptop;
}

const ExternalSide& Scenario::external_of(std::size_t team) const noexcept {
  return team < teams.size() && teams[team].external ? *teams[team].external : external;
}

namespace detail {
namespace {

const std::vector<std::string>& team_fields() {
  static const std::vector<std::string> fields = {"name", "attacks", "game_state", "laptop", "external", "robots"};
  return fields;
}
const std::vector<std::string>& robot_fields() {
  static const std::vector<std::string> fields = {"x_m",     "y_m",  "heading_deg", "interface", "agent",
                                                  "running", "role", "role_auto",   "emulate"};
  return fields;
}

void read_robot(const TableReader& r, Scenario& s) {
  physics::Placement at;
  if (const auto v = r.number("x_m", -100, 100)) at.x_m = *v;
  if (const auto v = r.number("y_m", -100, 100)) at.y_m = *v;
  if (const auto v = r.number("heading_deg", -360, 360)) at.heading_deg = *v;
  s.world.robots.push_back(at);
  if (const auto v = r.text("interface", "\"vcan0\"")) {
    if (v->size() > 15) r.fail(*r.get("interface"), "interface", "an interface name has at most 15 characters");
    s.interfaces.push_back(*v);
  } else {
    s.interfaces.emplace_back();  // complete() names it
  }
  if (const toml::node* n = r.get("agent")) {
    const auto v = n->value<std::int64_t>();
    if (!v || !n->is_integer() || *v < kFirstAgent || *v > kLastAgent) {
      r.fail(*n, "agent", "agent numbers are whole numbers 1..6 (each team has its own)");
    }
    s.agents.push_back(static_cast<int>(*v));
  } else {
    s.agents.push_back(0);  // complete() numbers it
  }
  // Not given: [run].emulate's, else all (parse_scenario fills it in).
  s.emulate.push_back(r.get("emulate") != nullptr ? r.node_set(*r.get("emulate"), "emulate") : can_nodes::NodeSet());
  CoachPlayer p;
  if (const auto v = r.boolean("running")) p.running = *v;
  if (const auto v = r.text("role", "\"striker\"")) p.role = *v;
  if (const auto v = r.boolean("role_auto")) p.role_auto = *v;
  s.coach.players.push_back(p);
}

}  // namespace

bool read_teams(const toml::table& root, const std::string& file, Scenario& s) {
  const toml::node* node = root.get("teams");
  if (node == nullptr) return false;
  const auto fail = [&](const toml::node& at, const std::string& field, const std::string& what) {
    throw physics::ConfigError(file, static_cast<int>(at.source().begin.line), field, what);
  };
  const toml::array* teams = node->as_array();
  if (teams == nullptr || teams->empty() || !teams->is_array_of_tables()) {
    fail(*node, "teams", "give each team as a [[teams]] table");
  }
  if (teams->size() > kMostTeams) fail((*teams)[kMostTeams], "teams", "a run has two teams at most");
  if (const toml::node* robots = root.get("robots")) {
    fail(*robots, "robots", "with [[teams]], place each robot in its team's [[teams.robots]]");
  }
  std::vector<std::string> game_states;
  for (const toml::node& t : *teams) {
    const toml::table& table = *t.as_table();
    const TableReader r(table, "teams", file, team_fields());
    Team team;
    team.name = r.text("name", "\"new\"").value_or("team " + std::to_string(s.teams.size() + 1));
    const bool plain = std::all_of(team.name.begin(), team.name.end(), [](char c) {
      return std::isprint(static_cast<unsigned char>(c)) != 0 && c != ',' && c != '"';
    });
    if (team.name.empty() || team.name.size() > 32 || !plain) {
      r.fail(*r.get("name"), "name", "1 to 32 printable characters without commas or quotes (it goes into CSV logs)");
    }
    if (const auto v = r.text("attacks", "\"+x\" or \"-x\"")) {
      if (*v != "+x" && *v != "-x") r.fail(*r.get("attacks"), "attacks", "the goal it attacks: \"+x\" or \"-x\"");
      team.attacks_positive_x = *v == "+x";
    } else {
      team.attacks_positive_x = s.teams.empty();  // the first +x, the second -x
    }
    game_states.push_back(r.text("game_state", "\"start\"").value_or(""));
    if (!game_states.back().empty() && !is_game_state(game_states.back())) {
      r.fail(*r.get("game_state"), "game_state", "\"" + game_states.back() + "\" is not a game state (as [coach])");
    }
    if (const toml::node* l = r.get("laptop")) {
      if (!l->is_table()) r.fail(*l, "laptop", "give it as a [teams.laptop] table");
      team.laptop.emplace();
      read_laptop(TableReader(*l->as_table(), "teams.laptop", file, laptop_fields()), *team.laptop);
    }
    if (const toml::node* e = r.get("external")) {
      if (!e->is_table()) r.fail(*e, "external", "give it as a [teams.external] table");
      team.external.emplace();
      read_external(TableReader(*e->as_table(), "teams.external", file, external_fields()), *team.external);
    }
    const toml::node* robots = r.get("robots");
    if (robots == nullptr || !robots->is_array_of_tables() || robots->as_array()->empty()) {
      r.fail(robots != nullptr ? *robots : t, "robots", "a team needs its robots: one [[teams.robots]] each");
    }
    team.first_robot = s.world.robots.size();
    for (const toml::node& rb : *robots->as_array()) {
      read_robot(TableReader(*rb.as_table(), "teams.robots", file, robot_fields()), s);
    }
    team.robots = s.world.robots.size() - team.first_robot;
    s.teams.push_back(std::move(team));
  }
  if (std::any_of(game_states.begin(), game_states.end(), [](const auto& g) { return !g.empty(); })) {
    s.coach.team_game_states = std::move(game_states);  // "" filled with [coach]'s by complete()
  }
  return true;
}

void complete_teams(Scenario& s) {
  const std::size_t robots = s.world.robots.size();
  if (s.teams.empty()) s.teams.push_back(Team{"canhil", true, 0, robots, std::nullopt, std::nullopt});
  if (s.teams.size() > kMostTeams) {
    throw SetupError("a run has two teams at most; this one has " + std::to_string(s.teams.size()));
  }
  std::size_t next = 0;
  std::set<std::string> names;
  for (const Team& t : s.teams) {
    if (t.first_robot != next || t.robots == 0) {
      throw SetupError("team " + t.name + " must hold the robots after the previous team's, at least one");
    }
    if (!names.insert(t.name).second) throw SetupError("two teams are named " + t.name + "; give each its own name");
    next += t.robots;
  }
  if (next != robots) {
    throw SetupError("the teams hold " + std::to_string(next) + " robots, the world places " + std::to_string(robots) +
                     ": every robot plays in one team");
  }
  if (s.teams.size() == 2 && s.teams[0].attacks_positive_x == s.teams[1].attacks_positive_x) {
    throw SetupError("both teams attack the " + std::string(s.teams[0].attacks_positive_x ? "+x" : "-x") +
                     " goal; give the second attacks = \"" + (s.teams[0].attacks_positive_x ? "-x" : "+x") + "\"");
  }
  if (!s.coach.team_game_states.empty()) {
    s.coach.team_game_states.resize(s.teams.size());
    for (std::string& g : s.coach.team_game_states) {
      if (g.empty()) g = s.coach.game_state;
      if (!is_game_state(g)) throw SetupError("\"" + g + "\" is not a game state (emulator/coach.hpp lists them)");
    }
  }
}

}  // namespace detail
}  // namespace canhil::emulator
