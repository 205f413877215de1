// Whole matches in virtual time (match.hpp): halves, ends changed at half
// time, and the tally taken from the world after every step.
#include "canhil/emulator/match.hpp"

#include <chrono>
#include <cmath>
#include <limits>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/virtual_driver.hpp"

namespace canhil::emulator {
namespace {

// The figures of one half, read from the world after every step.
class HalfTally {
 public:
  HalfTally(const Session& session, const MatchOptions& match) : session_(session), match_(match) {
    const Scenario& s = session.scenario();
    tally_.resize(s.teams.size());
    last_kick_.assign(s.robot_count(), -1.0);
    for (std::size_t r = 0; r < s.robot_count(); ++r) last_kick_[r] = session.world().robot(r).last_kick_time_s();
  }

  void step(Nanos now, Nanos period) {
    const physics::World& world = session_.world();
    const Scenario& s = session_.scenario();
    const Eigen::Vector3d ball = world.ball_position();
    const double dt = to_seconds(period);
    for (std::size_t r = 0; r < s.robot_count(); ++r) {
      const double kicked = world.robot(r).last_kick_time_s();
      if (kicked == last_kick_[r]) continue;
      last_kick_[r] = kicked;
      const std::size_t team = s.team_of(r);
      ++tally_[team].kicks;
      shots_due_.push_back({now + from_seconds(match_.shot_check_s), team});
    }
    for (auto it = shots_due_.begin(); it != shots_due_.end();) {
      if (now < it->at) {
        ++it;
        continue;
      }
      if (at_goal(ball, world.ball_velocity(), s.teams[it->team].attacks_positive_x)) ++tally_[it->team].shots;
      it = shots_due_.erase(it);
    }
    const Referee* referee = session_.referee();
    if (referee != nullptr && !referee->in_play()) return;
    std::size_t nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < s.robot_count(); ++r) {
      const kinematics::Pose p = world.robot(r).pose();
      const double d = std::hypot(p.x_m - ball.x(), p.y_m - ball.y());
      if (d < best) {
        best = d;
        nearest = r;
      }
    }
    if (best <= match_.possession_reach_m) tally_[s.team_of(nearest)].possession_s += dt;
  }

  std::vector<TeamTally>& tally() { return tally_; }

 private:
  // The ball on its way to the goal at +x (or -x), on a line between the posts.
  bool at_goal(const Eigen::Vector3d& ball, const Eigen::Vector3d& velocity, bool positive_x) const {
    const physics::FieldParams& field = session_.scenario().world.field;
    const double goal_x = positive_x ? field.length_m / 2 : -field.length_m / 2;
    const double vx = velocity.x();
    if ((positive_x ? vx : -vx) < 0.5) return false;  // not going that way
    const double t = (goal_x - ball.x()) / vx;
    if (t < 0) return false;
    return std::fabs(ball.y() + velocity.y() * t) < field.goal.width_m / 2;
  }

  struct ShotDue {
    Nanos at{0};
    std::size_t team = 0;
  };
  const Session& session_;
  const MatchOptions& match_;
  std::vector<TeamTally> tally_;
  std::vector<double> last_kick_;
  std::vector<ShotDue> shots_due_;
};

// canhil's in-process reference handler and agent, the FTT check on.
class ReferenceHalf final : public HalfDriver {
 public:
  ReferenceHalf(Session& session, bool keep_trace) : driver_(session, options(keep_trace)) {}
  void run_until(Nanos end) override { driver_.run_until(end); }
  Nanos now() const override { return driver_.now(); }
  std::uint64_t ftt_violations(std::size_t robot) const override { return driver_.ftt_violations(robot); }
  std::uint64_t trace_hash() const override { return driver_.trace_hash(); }
  std::string trace() const override { return driver_.trace(); }

 private:
  static VirtualOptions options(bool keep_trace) {
    VirtualOptions o;
    o.record_trace = keep_trace;
    o.check_timing = true;
    return o;
  }
  VirtualDriver driver_;
};

}  // namespace

TeamTally& TeamTally::operator+=(const TeamTally& o) {
  goals += o.goals;
  possession_s += o.possession_s;
  shots += o.shots;
  kicks += o.kicks;
  faults += o.faults;
  ftt_violations += o.ftt_violations;
  return *this;
}

std::optional<std::size_t> MatchResult::winner() const {
  if (teams.size() != 2 || teams[0].goals == teams[1].goals) return std::nullopt;
  return teams[0].goals > teams[1].goals ? 0 : 1;
}

std::uint64_t half_seed(std::uint64_t seed, int half) noexcept {
  constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15;  // apart for every half, and 0 for the first
  return seed + static_cast<std::uint64_t>(half) * kGolden;
}

MatchResult play_match(const Scenario& scenario, const SessionOptions& options, const MatchOptions& match,
                       const std::function<void(double)>& progress, const std::atomic<bool>* stop) {
  if (scenario.teams.size() != 2) {
    throw SetupError("a match needs two teams ([[teams]] twice in the scenario); this one has " +
                     std::to_string(scenario.teams.size()));
  }
  if (!scenario.referee.enabled.value_or(true)) {
    throw SetupError("a match needs the referee (its [referee] says enabled = false); switch single rules off instead");
  }
  if (match.halves < 1 || !(match.half_s > 0)) throw SetupError("a match has at least one half of more than 0 s");
  MatchResult result;
  const std::uint64_t seed = match.overrides.seed.value_or(scenario.seed);
  result.seed = seed;
  result.teams.resize(2);
  const auto wall_start = std::chrono::steady_clock::now();
  double played = 0;
  SessionOptions half_options = options;
  if (match.keep_logs) half_options.world_log_period = match.world_log_period;
  for (int half = 0; half < match.halves && !result.stopped; ++half) {
    RunOverrides half_overrides = match.overrides;
    half_overrides.half = half;
    half_overrides.seed = half_seed(seed, half);
    half_overrides.duration_s = match.half_s;
    Session session(plan_run(scenario, half_options, half_overrides));
    const std::unique_ptr<HalfDriver> driving =
        match.driver ? match.driver(session, seed, half) : std::make_unique<ReferenceHalf>(session, match.keep_logs);
    HalfDriver& driver = *driving;
    HalfTally tally(session, match);
    session.on_step([&](Nanos now) { tally.step(now, session.step_period()); });
    const Nanos end = from_seconds(match.half_s);
    while (driver.now() < end) {
      driver.run_until(std::min(end, driver.now() + std::chrono::seconds(1)));
      if (progress) progress(played + to_seconds(driver.now()));
      if (stop != nullptr && stop->load()) {
        result.stopped = true;
        break;
      }
    }
    session.on_step(nullptr);
    played += to_seconds(driver.now());
    std::vector<TeamTally>& half_tally = tally.tally();
    for (const Goal& g : session.goals()) {  // the team that attacks that goal scored
      const std::size_t team = session.scenario().teams[0].attacks_positive_x == g.positive_x ? 0 : 1;
      ++half_tally[team].goals;
      result.goals.push_back({half, to_seconds(g.time), team});
    }
    if (const Referee* referee = session.referee()) {
      for (const RefereeCall& c : referee->calls())
        result.calls.push_back({half, to_seconds(c.time), std::string(restart_name(c.restart)), c.team, c.text});
      result.referee_calls += referee->calls().size();
    }
    if (match.half_ended) match.half_ended(session, driver, seed, half);
    result.solver.add(session.world().solver_health());
    result.timing += session.step_timing();
    for (std::size_t r = 0; r < session.robot_count(); ++r) {
      TeamTally& t = half_tally[session.rig(r).team];
      for (const can_nodes::FaultCount& c : session.rig(r).faults->counts()) t.faults += c.applied;
      t.ftt_violations += driver.ftt_violations(r);
    }
    for (std::size_t t = 0; t < 2; ++t) result.teams[t] += half_tally[t];
    result.trace_hash = result.trace_hash * 0x100000001b3ULL ^ driver.trace_hash();
  }
  result.virtual_s = played;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace canhil::emulator
