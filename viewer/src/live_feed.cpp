#include "canhil/viewer/live_feed.hpp"

#include "canhil/can_nodes/fault.hpp"
#include "canhil/control/save_commands.hpp"

namespace canhil::viewer {

using nlohmann::json;

json world_hello(const physics::WorldParams& w) {
  const physics::FieldParams& f = w.field;
  json game_states = json::array();
  for (const auto g : emulator::kGameStates) game_states.push_back(std::string(g));
  return {{"field",
           {{"length_m", f.length_m},
            {"width_m", f.width_m},
            {"line_width_m", f.line_width_m},
            {"centre_circle_radius_m", f.centre_circle_radius_m},
            {"goal_area_depth_m", f.goal_area_depth_m},
            {"goal_area_width_m", f.goal_area_width_m},
            {"penalty_area_depth_m", f.penalty_area_depth_m},
            {"penalty_area_width_m", f.penalty_area_width_m},
            {"corner_arc_radius_m", f.corner_arc_radius_m},
            {"penalty_mark_distance_m", f.penalty_mark_distance_m},
            {"margin_m", f.margin_m},
            {"goal_width_m", f.goal.width_m},
            {"goal_depth_m", f.goal.depth_m},
            {"goal_height_m", f.goal.height_m}}},
          {"ball_radius_m", w.ball.radius_m},
          {"robot_radius_m", w.robot.body_radius_m},
          {"game_states", game_states}};
}

LiveFeed::LiveFeed(emulator::Session& session, control::Commands& commands, emulator::RunControl* control,
                   std::filesystem::path save_folder)
    : session_(session), commands_(commands), control_(control), save_folder_(std::move(save_folder)) {}

json LiveFeed::hello() {
  const emulator::Scenario& sc = session_.scenario();
  json h = world_hello(sc.world);
  h["mode"] = "live";
  json robots = json::array();
  for (std::size_t r = 0; r < session_.robot_count(); ++r) {
    const emulator::Rig& rig = session_.rig(r);
    robots.push_back({{"index", r}, {"agent", rig.agent}, {"interface", rig.interface}, {"team", rig.team}});
  }
  h["robots"] = robots;
  json teams = json::array();
  for (const emulator::Team& t : sc.teams)
    teams.push_back({{"name", t.name}, {"attacks_positive_x", t.attacks_positive_x}});
  h["teams"] = teams;
  json obstacles = json::array();
  for (std::size_t o = 0; o < sc.world.obstacles.size(); ++o) {
    const physics::ObstacleParams& p = sc.world.obstacles[o].params;
    obstacles.push_back({{"index", o}, {"radius_m", p.radius_m}, {"height_m", p.height_m}, {"movable", p.movable}});
  }
  h["obstacles"] = obstacles;
  h["ec_s"] = to_seconds(session_.options().ftt.elementary_cycle);
  h["virtual_time"] = control_ != nullptr;
  json faults = json::array();
  for (const char* f : kFaultExamples) faults.push_back(f);
  h["faults"] = faults;
  json saves = json::array();
  for (const auto& [name, kind] : control::list_saves(save_folder_)) saves.push_back({{"name", name}, {"kind", kind}});
  h["saves"] = saves;
  h["save_folder"] = std::filesystem::absolute(save_folder_).string();
  return h;
}

json LiveFeed::state() {
  json s = control::to_json(session_.detailed_snapshot());
  s["paused"] = control_ != nullptr && control_->paused();
  s["speed"] = control_ != nullptr ? control_->speed() : 1.0;
  s["ended"] = ended_.load();
  {
    // Virtual seconds per wall second, smoothed over the last second or so.
    const std::lock_guard lock(rate_mutex_);
    const auto wall = std::chrono::steady_clock::now();
    const double t = s["time_s"].get<double>();
    if (last_time_s_ >= 0) {
      const double dw = std::chrono::duration<double>(wall - last_wall_).count();
      if (dw > 0) rate_ = 0.8 * rate_ + 0.2 * std::max(0.0, t - last_time_s_) / dw;
    }
    last_time_s_ = t;
    last_wall_ = wall;
    s["real_time_factor"] = rate_;
  }
  return s;
}

json LiveFeed::request(std::string_view text) { return commands_.handle_text(text, "viewer"); }

}  // namespace canhil::viewer
