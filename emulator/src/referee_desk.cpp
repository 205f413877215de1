#include "canhil/emulator/referee_desk.hpp"

#include <cmath>
#include <numbers>

namespace canhil::emulator {
namespace {

std::vector<RefereeTeam> referee_teams(const Scenario& s) {
  std::vector<RefereeTeam> teams;
  for (const Team& t : s.teams) teams.push_back({t.name, t.attacks_positive_x, t.first_robot, t.robots});
  return teams;
}

}  // namespace

RefereeDesk::RefereeDesk(const Scenario& scenario)
    : scenario_(scenario),
      referee_(scenario.world, referee_teams(scenario), scenario.referee, scenario.seed),
      placements_(scenario.robot_count(), 0) {}

RefereeDesk::Outcome RefereeDesk::step(physics::World& world, Nanos now, std::optional<bool> goal_positive_x) {
  RefereeView& v = view_;
  v.ball = world.ball_position();
  v.ball_velocity = world.ball_velocity();
  v.robots.resize(placements_.size());
  for (std::size_t r = 0; r < v.robots.size(); ++r) {
    const kinematics::Pose p = world.robot(r).pose();
    v.robots[r] = {p.x_m, p.y_m};
  }
  Outcome out;
  out.call = referee_.step(v, now, goal_positive_x);
  if (out.call) {
    carry_out(world, *out.call);
  } else {
    out.resume = referee_.resume_due(now);
  }
  return out;
}

// The ball to its spot; at a kick-off the robots back to their places.
void RefereeDesk::carry_out(physics::World& world, const RefereeCall& call) {
  world.place_ball({call.spot.x(), call.spot.y(), scenario_.world.ball.radius_m}, Eigen::Vector3d::Zero());
  if (call.restart == Restart::kKickoff) {
    for (std::size_t r = 0; r < placements_.size(); ++r) {
      world.robot(r).place(scenario_.world.robots[r]);
      ++placements_[r];
    }
  } else {
    keep_away_from(world, call.spot);
  }
}

// Every robot keeps its distance from a restart: one nearer steps back towards
// its own goal, to the first place on the field that no other robot or
// obstacle takes (robots placed into each other would be thrown apart).
void RefereeDesk::keep_away_from(physics::World& world, const Eigen::Vector2d& spot) {
  const double distance = scenario_.referee.restart_distance_m;
  const physics::WorldParams& w = scenario_.world;
  const double radius = w.robot.body_radius_m;
  std::vector<Eigen::Vector2d> at(placements_.size());
  for (std::size_t r = 0; r < at.size(); ++r) {
    const kinematics::Pose p = world.robot(r).pose();
    at[r] = {p.x_m, p.y_m};
  }
  const auto free = [&](const Eigen::Vector2d& c, std::size_t self) {
    if (std::fabs(c.x()) > w.field.length_m / 2 - radius || std::fabs(c.y()) > w.field.width_m / 2 - radius) {
      return false;
    }
    if ((c - spot).norm() < distance) return false;
    for (std::size_t o = 0; o < at.size(); ++o) {
      if (o != self && (at[o] - c).norm() < 2 * radius + 0.1) return false;
    }
    for (std::size_t o = 0; o < w.obstacles.size(); ++o) {
      const Eigen::Vector3d ob = world.obstacle_position(o);
      if (Eigen::Vector2d(ob.x() - c.x(), ob.y() - c.y()).norm() < radius + w.obstacles[o].params.radius_m + 0.1) {
        return false;
      }
    }
    return true;
  };
  for (std::size_t r = 0; r < at.size(); ++r) {
    if ((at[r] - spot).norm() >= distance) continue;
    const double own = scenario_.teams[scenario_.team_of(r)].attacks_positive_x ? -1.0 : 1.0;
    std::optional<Eigen::Vector2d> place;
    for (double back = distance; back <= distance + 3.0 && !place; back += 0.5) {
      for (const double side : {0.0, 0.6, -0.6, 1.2, -1.2, 1.8, -1.8}) {
        const Eigen::Vector2d c(spot.x() + own * back, at[r].y() + side);
        if (free(c, r)) {
          place = c;
          break;
        }
      }
    }
    if (!place) continue;  // nowhere free near: it stays
    at[r] = *place;
    const double heading_deg = world.robot(r).pose().heading_rad * 180.0 / std::numbers::pi;
    world.robot(r).place({place->x(), place->y(), heading_deg});
    ++placements_[r];
  }
}

}  // namespace canhil::emulator
