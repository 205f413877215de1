// canhil/emulator/match.hpp — whole matches in virtual time (`canhil
// match`): halves of a set length, each a fresh session of the scenario with
// the teams changing ends at half time, the referee on, and a tally per team
// taken from the world as it steps: goals, possession, shots, kicks, the
// frames the scenario's fault rules changed and the FTT violations on the
// team's buses. One seed gives one match; each half has a seed of its own
// drawn from it.
//
// Thread-compatible: one thread plays a match.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canhil/emulator/run_plan.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/step_timing.hpp"

namespace canhil::emulator {

/// What drives one half's session in virtual time: canhil's in-process
/// reference handler and agent (VirtualDriver) unless the match is given
/// another, such as the team's own processes in lockstep (`canhil match
/// --external`).
class HalfDriver {
 public:
  virtual ~HalfDriver() = default;
  /// Runs until the virtual clock reads `end`.
  virtual void run_until(Nanos end) = 0;
  virtual Nanos now() const = 0;
  /// The FTT and timing violations on robot r's bus so far.
  virtual std::uint64_t ftt_violations(std::size_t robot) const = 0;
  /// A hash of every frame on the half's buses so far (BusWatch::trace_hash).
  virtual std::uint64_t trace_hash() const = 0;
  /// Every frame on the half's buses so far as a candump -l log, when the
  /// match keeps its logs (MatchOptions::keep_logs); else empty.
  virtual std::string trace() const = 0;
};

/// Makes the driver of half `half` (0-based) of the match with seed `seed`,
/// on its fresh session; the driver is destroyed before the session.
using HalfDriverMaker = std::function<std::unique_ptr<HalfDriver>(Session&, std::uint64_t seed, int half)>;

struct MatchOptions {
  int halves = 2;
  double half_s = 600;  ///< virtual seconds per half
  /// What the command says over the scenario for every half (`--process`,
  /// `--answer-limit`) and the match's seed (none: the scenario's); each
  /// half's plan adds its half, its seed (half_seed) and its length.
  RunOverrides overrides;
  /// A team has the ball while, in play, one of its robots is the nearest to
  /// the ball and within this distance of its centre.
  double possession_reach_m = 1.0;
  /// A shot: a kick after which the ball, this long later, is moving towards
  /// the goal the kicker's team attacks on a line between the posts.
  double shot_check_s = 0.05;
  /// None: the in-process reference handler and agent on every robot.
  HalfDriverMaker driver;
  /// Each half keeps its frames (HalfDriver::trace) and a world log (one row
  /// every world_log_period), for half_ended: what `canhil match --logs`
  /// writes, so that a half can be looked at (`canhil view`) without
  /// playing it again. Off, a match keeps its figures only.
  bool keep_logs = false;
  Nanos world_log_period = std::chrono::milliseconds(50);
  /// Called at the end of each half (0-based) of the match with seed `seed`,
  /// its session and driver still there.
  std::function<void(const Session&, const HalfDriver&, std::uint64_t seed, int half)> half_ended;
};

/// One of the referee's calls in a match.
struct MatchCall {
  int half = 0;
  double time_s = 0;                ///< into the half
  std::string restart;              ///< restart_name()'s words: "kickoff", "goalkick", ...
  std::optional<std::size_t> team;  ///< the team that takes it; none: a dropped ball
  std::string text;                 ///< for people: "goal for new (+x), kick-off old"
};

/// A team's figures over a match (or a half).
struct TeamTally {
  int goals = 0;
  double possession_s = 0;
  int shots = 0;
  int kicks = 0;                     ///< kicks its robots fired (the world's count, whoever asked)
  std::uint64_t faults = 0;          ///< frames the scenario's fault rules changed on its buses
  std::uint64_t ftt_violations = 0;  ///< on its buses, by `canhil timing`'s rules
  TeamTally& operator+=(const TeamTally& other);
};

struct MatchGoal {
  int half = 0;
  double time_s = 0;  ///< into the half
  std::size_t team = 0;
};

struct MatchResult {
  std::uint64_t seed = 0;
  std::vector<TeamTally> teams;  ///< in the scenario's order
  std::vector<MatchGoal> goals;
  std::size_t referee_calls = 0;
  std::vector<MatchCall> calls;  ///< every call, in order (a record read back may have only the count)
  physics::SolverHealth solver;  ///< what ODE reported over every half
  double virtual_s = 0;
  double wall_s = 0;
  /// Every half's BusWatch::trace_hash, combined in order: the same match
  /// (scenario, seed, binaries) gives the same hash on any machine.
  std::uint64_t trace_hash = 0;
  /// The world's steps and the vision over every half, with
  /// SessionOptions::time_steps.
  StepTiming timing;
  bool stopped = false;  ///< cut short (the stop flag): the figures so far
  /// The winner's index; none for a draw.
  std::optional<std::size_t> winner() const;
};

/// The seed of one half of the match with seed `seed`.
std::uint64_t half_seed(std::uint64_t seed, int half) noexcept;

/// Plays a match of `scenario` (two teams; the match's seed is
/// match.overrides.seed, else the scenario's) with the
/// in-process reference handler and agent on every robot, or what
/// `match.driver` makes. `progress` is
/// called after each virtual second with the virtual seconds played so far;
/// `stop`, when set, ends the match after the current second. SetupError for
/// a scenario without two teams, or with its referee switched off.
MatchResult play_match(const Scenario& scenario, const SessionOptions& options, const MatchOptions& match,
                       const std::function<void(double played_s)>& progress = {},
                       const std::atomic<bool>* stop = nullptr);

}  // namespace canhil::emulator
