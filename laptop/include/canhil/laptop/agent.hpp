// canhil/laptop/agent.hpp — the reference agent's decisions, as a pure
// function of what it knows. Simple and readable on purpose: a model for a
// team's own agent, not a competitor.
//
//   search    no ball seen: turn on the spot
//   approach  drive to the ball, facing it; grabber on when near
//   aim       ball held (the barrier says so): turn towards the opponent goal
//   kick      aimed for a few frames: one kick, then cool down and search again
//   wait      the other team's restart: keep off the ball until it is in play
//
// It plays only while the coach lets it (the game state "start", or no coach
// yet); in every other game state (stop, halt, a restart's pause, parking)
// it stands still, grabber off, and kicks nothing. A "start" after the other
// team's restart ("their_kickoff", "their_goalkick", ...) lets the other team
// take it: the agent waits, turning on the spot, until it sees the ball
// restart_moved_m from where it first saw it after "start", or for at most
// restart_wait_s (a restart the other team does not take); then it plays.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace canhil::laptop {

struct AgentConfig {
  double goal_x_m = 9.0;  ///< the opponent goal's centre, world frame
  double goal_y_m = 0.0;
  double max_speed_mps = 1.5;
  double grabber_distance_m = 1.0;
  double aim_tolerance_rad = 0.06;
  int aimed_frames = 3;  ///< frames inside the tolerance before kicking
  int kick_power = 40;   ///< 1..50
  bool low_kick = true;  ///< along the carpet; false lobs
  double cooldown_s = 1.0;
  double restart_moved_m = 0.5;  ///< after the other team's restart: the ball moved this far is in play
  double restart_wait_s = 7.0;   ///< ... and so is one the other team left this long after "start"
};

struct AgentInput {
  bool ball_seen = false;
  double ball_x_m = 0, ball_y_m = 0;  ///< robot frame: x right, y forward
  double x_m = 0, y_m = 0;            ///< own pose (odometry), world frame
  double heading_rad = 0;             ///< yaw of the robot's +x axis; its front points at heading + pi/2
  bool ball_engaged = false;
  bool play = true;            ///< the coach's game state lets it play ("start", or none written yet)
  bool their_restart = false;  ///< the game state is a restart the other team takes ("their_kickoff", ...)
  double dt_s = 1.0 / 30;      ///< since the last decision
};

enum class AgentState : std::uint8_t { kSearch, kApproach, kAim, kCooldown, kWait };
const char* state_name(AgentState s) noexcept;

struct AgentOutput {
  double vx_mps = 0, vy_mps = 0, va_radps = 0;  ///< robot frame
  int grabber = 0;                              ///< 0..100
  std::uint8_t kick = 0;                        ///< the M7 kick byte; 0 = no kick this frame
};

class Agent {
 public:
  explicit Agent(const AgentConfig& config = {}) : config_(config) {}
  AgentOutput decide(const AgentInput& in);
  AgentState state() const noexcept { return state_; }
  int kicks() const noexcept { return kicks_; }

 private:
  bool restart_taken(const AgentInput& in);

  AgentConfig config_;
  AgentState state_ = AgentState::kSearch;
  int aimed_ = 0;
  double cooldown_left_ = 0;
  int kicks_ = 0;
  bool their_restart_ = false;  // the last game state before "start" was the other team's restart
  double waited_s_ = 0;         // since "start", while their_restart_
  std::optional<std::array<double, 2>> restart_ball_;  // where it first saw the ball then, world frame
};

}  // namespace canhil::laptop
