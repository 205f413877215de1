// canhil/emulator/coach.hpp — the base station's orders to the robots: the
// game state (the referee's signal as the coach relays it) and, per robot,
// whether it plays, in which role and how often canhil has moved it. A
// scenario sets them ([coach]); a running session changes them (SetCoach:
// canhil coach, the viewer, the referee; a robot carried or moved counts a
// relocation); the coach writer puts them into every robot's RTDB as the team's
// base station does (COACH_INFO, FORMATION_INFO in the team's layout).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace canhil::emulator {

/// The game states canhil knows, by name (a layout maps each to the team's value).
inline constexpr std::array<std::string_view, 20> kGameStates = {
    "stop",          "start",          "halt",          "ready",          "drop_ball",  "our_kickoff",  "their_kickoff",
    "our_freekick",  "their_freekick", "our_goalkick",  "their_goalkick", "our_corner", "their_corner", "our_throwin",
    "their_throwin", "our_penalty",    "their_penalty", "our_goal",       "their_goal", "parking"};

/// True when `name` is one of kGameStates.
bool is_game_state(std::string_view name) noexcept;

struct CoachPlayer {
  bool running = true;           ///< the base station lets it play
  std::string role = "striker";  ///< a role the team's layout names
  bool role_auto = true;         ///< the agent picks its role itself
  /// How many times the robot was moved by canhil (the referee's placements,
  /// a robot moved by the viewer or a control command), each counted
  /// LaptopSide::relocation_delay_s after the move: a new value tells the
  /// team's agent to find itself again (COACH_INFO `relocations`; CAMBADA's
  /// changePositionSN, which its base station bumps when a robot is moved by
  /// hand). The run's, never a scenario's: it starts at 0.
  std::uint32_t relocations = 0;
  friend bool operator==(const CoachPlayer&, const CoachPlayer&) = default;
};

struct CoachState {
  std::string game_state = "start";  ///< every team's, unless team_game_states says otherwise
  std::vector<CoachPlayer> players;  ///< one per robot (of every team, in the scenario's order)
  /// Each team's own game state (two teams: "our_kickoff" for one is
  /// "their_kickoff" for the other); empty: game_state for all.
  std::vector<std::string> team_game_states;
  /// The goal the team attacks (a team's own coach state, Session::team_coach:
  /// its Team's attacks; a layout's COACH_INFO `attacks` tells its agents).
  bool attacks_positive_x = true;
  const std::string& state_of(std::size_t team) const noexcept {
    return team < team_game_states.size() ? team_game_states[team] : game_state;
  }
  friend bool operator==(const CoachState&, const CoachState&) = default;
};

/// A change of the coach's orders: the game state (of one team, or of all),
/// or one robot's (what is given).
struct SetCoach {
  std::optional<std::string> game_state;
  std::optional<std::size_t> robot;
  std::optional<bool> running;
  std::optional<std::string> role;
  std::optional<std::size_t> team;  ///< with game_state: only this team's
};

}  // namespace canhil::emulator
