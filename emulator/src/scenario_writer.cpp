#include "canhil/emulator/scenario_writer.hpp"

#include <toml++/toml.h>
#include <cmath>
#include <filesystem>
#include <sstream>

namespace canhil::emulator {
namespace {

double degrees(double rad) { return rad * 180.0 / M_PI; }

// Rounded to 0.1 mm and 0.01 deg: a saved scenario reads like a written one.
double rounded(double v, double step) { return std::round(v / step) * step; }

std::string absolute(const std::string& path) {
  if (path.empty() || path == "builtin" || path == "none" || path == "canhil" || path == "cambada") return path;
  std::error_code ec;
  const auto a = std::filesystem::absolute(path, ec);
  return ec ? path : a.string();
}

}  // namespace

std::string scenario_toml(const Scenario& sc, const WorldSnapshot& now) {
  toml::table root;
  if (!sc.source_toml.empty()) root = toml::parse(sc.source_toml);  // it was parsed once already
  for (const char* key : {"run", "coach", "robots", "obstacles", "ball_start", "laptop"}) root.erase(key);

  toml::table run{{"seed", static_cast<std::int64_t>(sc.seed)}, {"kick_power", sc.kick_power}};
  // Only a length the scenario gave: without one a real-time run goes on until Ctrl-C.
  if (sc.duration_given) run.insert("duration_s", sc.duration_s);
  toml::array interfaces, agents, faults;
  for (const auto& i : sc.interfaces) interfaces.push_back(i);
  for (const int a : sc.agents) agents.push_back(a);
  for (const auto& f : sc.faults) faults.push_back(f.text);
  run.insert("interfaces", std::move(interfaces));
  run.insert("agents", std::move(agents));
  if (!faults.empty()) run.insert("faults", std::move(faults));
  if (sc.mixes_real_boards() && !root.contains("teams")) {  // (teams keep theirs in [[teams.robots]])
    toml::array emulate;
    for (const can_nodes::NodeSet set : sc.emulate) {
      toml::array names;
      for (std::size_t i = 0; i < can_nodes::kNodeCount; ++i) {
        const auto id = static_cast<can_nodes::NodeId>(i);
        if (set.contains(id)) names.push_back(can_nodes::node_name(id));
      }
      emulate.push_back(std::move(names));
    }
    run.insert("emulate", std::move(emulate));
  }
  root.insert("run", std::move(run));

  toml::table coach{{"game_state", now.coach.game_state}};
  toml::array running, roles, role_auto;
  for (const CoachPlayer& p : now.coach.players) {
    running.push_back(p.running);
    roles.push_back(p.role);
    role_auto.push_back(p.role_auto);
  }
  coach.insert("running", std::move(running));
  coach.insert("roles", std::move(roles));
  coach.insert("role_auto", std::move(role_auto));
  root.insert("coach", std::move(coach));

  const LaptopSide& l = sc.laptop;
  toml::table laptop;
  if (!l.rtdb_lib.empty()) laptop.insert("rtdb_lib", absolute(l.rtdb_lib));
  if (!l.rtdb_items.empty()) laptop.insert("rtdb_items", absolute(l.rtdb_items));
  if (!l.rtdb_ini.empty()) laptop.insert("rtdb_ini", absolute(l.rtdb_ini));
  if (!l.layout.empty()) laptop.insert("layout", absolute(l.layout));
  if (!l.pman.empty()) laptop.insert("pman", absolute(l.pman));
  toml::array processes;
  for (const auto& p : l.pman_processes) processes.push_back(p);
  laptop.insert("pman_processes", std::move(processes));
  laptop.insert("coach_period_s", l.coach_period_s);
  laptop.insert("relocation_delay_s", l.relocation_delay_s);
  if (l.replicate) laptop.insert("replicate", *l.replicate);
  laptop.insert("replicate_period_s", l.replicate_period_s);
  root.insert("laptop", std::move(laptop));

  toml::array robots;
  for (const kinematics::Pose& p : now.robots) {
    robots.push_back(toml::table{{"x_m", rounded(p.x_m, 1e-4)},
                                 {"y_m", rounded(p.y_m, 1e-4)},
                                 {"heading_deg", rounded(degrees(p.heading_rad), 1e-2)}});
  }
  root.insert("robots", std::move(robots));
  toml::array obstacles;
  for (std::size_t o = 0; o < now.obstacles.size() && o < sc.world.obstacles.size(); ++o) {
    const physics::ObstacleParams& op = sc.world.obstacles[o].params;
    obstacles.push_back(toml::table{{"x_m", rounded(now.obstacles[o].x(), 1e-4)},
                                    {"y_m", rounded(now.obstacles[o].y(), 1e-4)},
                                    {"radius_m", op.radius_m},
                                    {"height_m", op.height_m},
                                    {"mass_kg", op.mass_kg},
                                    {"friction", op.friction},
                                    {"movable", op.movable}});
  }
  if (!obstacles.empty()) root.insert("obstacles", std::move(obstacles));
  root.insert("ball_start", toml::table{{"x_m", rounded(now.ball.x(), 1e-4)},
                                        {"y_m", rounded(now.ball.y(), 1e-4)},
                                        {"z_m", rounded(now.ball.z(), 1e-4)}});
  std::ostringstream out;
  out << "# canhil scenario, saved from a running world (canhil run --config FILE)\n\n" << root << '\n';
  return out.str();
}

}  // namespace canhil::emulator
