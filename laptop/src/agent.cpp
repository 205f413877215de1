#include "canhil/laptop/agent.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace canhil::laptop {

const char* state_name(AgentState s) noexcept {
  switch (s) {
    case AgentState::kSearch:
      return "search";
    case AgentState::kApproach:
      return "approach";
    case AgentState::kAim:
      return "aim";
    case AgentState::kCooldown:
      return "cooldown";
  }
  return "?";
}

AgentOutput Agent::decide(const AgentInput& in) {
  constexpr double kPi = std::numbers::pi;
  AgentOutput out;
  if (!in.play) {
    // Waits for "start": still, grabber off, no aim carried over into the game.
    aimed_ = 0;
    if (state_ == AgentState::kAim || state_ == AgentState::kApproach) state_ = AgentState::kSearch;
    return out;
  }
  if (state_ == AgentState::kCooldown) {
    cooldown_left_ -= in.dt_s;
    if (cooldown_left_ > 0) return out;  // stand still while the ball leaves
    state_ = AgentState::kSearch;
  }
  if (in.ball_engaged) {
    state_ = AgentState::kAim;
  } else if (in.ball_seen) {
    state_ = AgentState::kApproach;
    aimed_ = 0;
  } else {
    state_ = AgentState::kSearch;
    aimed_ = 0;
  }
  switch (state_) {
    case AgentState::kSearch:
      out.va_radps = 1.0;
      break;
    case AgentState::kApproach: {
      const double dist = std::hypot(in.ball_x_m, in.ball_y_m);
      const double bearing = std::atan2(-in.ball_x_m, in.ball_y_m);  // from the front, counter-clockwise
      // Face the ball while driving to it; slow down when it is off to the side.
      out.va_radps = std::clamp(3.0 * bearing, -2.0, 2.0);
      const double speed = std::min(config_.max_speed_mps, 1.2 * dist) * std::max(0.2, std::cos(bearing));
      if (dist > 1e-6) {
        out.vx_mps = speed * in.ball_x_m / dist;
        out.vy_mps = speed * in.ball_y_m / dist;
      }
      out.grabber = dist < config_.grabber_distance_m ? 100 : 0;
      break;
    }
    case AgentState::kAim: {
      out.grabber = 100;
      const double to_goal = std::atan2(config_.goal_y_m - in.y_m, config_.goal_x_m - in.x_m);
      const double front = in.heading_rad + kPi / 2;
      const double error = std::remainder(to_goal - front, 2 * kPi);
      out.va_radps = std::clamp(3.0 * error, -1.5, 1.5);
      out.vy_mps = 0.05;  // lean on the ball so the grabber keeps it
      aimed_ = std::fabs(error) < config_.aim_tolerance_rad ? aimed_ + 1 : 0;
      if (aimed_ >= config_.aimed_frames) {
        const int power = std::clamp(config_.kick_power, 1, 50);
        out.kick = static_cast<std::uint8_t>((config_.low_kick ? 0x80 : 0) | power);
        out.va_radps = 0;
        out.vy_mps = 0;
        ++kicks_;
        aimed_ = 0;
        state_ = AgentState::kCooldown;
        cooldown_left_ = config_.cooldown_s;
      }
      break;
    }
    case AgentState::kCooldown:
      break;
  }
  return out;
}

}  // namespace canhil::laptop
