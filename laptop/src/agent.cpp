#include "canhil/laptop/agent.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace canhil::laptop {

namespace {

// A ball seen at (x right, y forward) of a robot at its odometry pose, in the world frame.
std::array<double, 2> ball_in_world(const AgentInput& in) {
  const double c = std::cos(in.heading_rad);
  const double s = std::sin(in.heading_rad);
  return {in.x_m + c * in.ball_x_m - s * in.ball_y_m, in.y_m + s * in.ball_x_m + c * in.ball_y_m};
}

}  // namespace

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
    case AgentState::kWait:
      return "wait";
  }
  return "?";
}

// The other team's restart is taken when the ball, as this robot sees it
// (robot frame, turned into the world's by its odometry), has moved
// restart_moved_m from where it first saw it after "start"; or after
// restart_wait_s, taken or not.
bool Agent::restart_taken(const AgentInput& in) {
  waited_s_ += in.dt_s;
  if (waited_s_ >= config_.restart_wait_s) return true;
  if (!in.ball_seen) return false;
  const std::array<double, 2> ball = ball_in_world(in);
  if (!restart_ball_) {
    restart_ball_ = ball;
    return false;
  }
  return std::hypot(ball[0] - (*restart_ball_)[0], ball[1] - (*restart_ball_)[1]) >= config_.restart_moved_m;
}

AgentOutput Agent::decide(const AgentInput& in) {
  constexpr double kPi = std::numbers::pi;
  AgentOutput out;
  if (!in.play) {
    // Waits for "start": still, grabber off, no aim carried over into the game.
    aimed_ = 0;
    if (state_ != AgentState::kCooldown) state_ = AgentState::kSearch;
    their_restart_ = in.their_restart;  // the last state before "start" decides
    waited_s_ = 0;
    restart_ball_.reset();
    return out;
  }
  if (their_restart_) {
    if (!restart_taken(in)) {
      // Theirs to take: off the ball, turning while it does not see it (to see it move).
      state_ = AgentState::kWait;
      if (!in.ball_seen) out.va_radps = 1.0;
      return out;
    }
    their_restart_ = false;
    state_ = AgentState::kSearch;
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
    case AgentState::kWait:
      break;
  }
  return out;
}

}  // namespace canhil::laptop
