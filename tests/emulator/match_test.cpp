// Whole matches in virtual time: halves with ends changed, a tally per team
// that adds up, one seed one match, faults and FTT violations counted for the
// team whose buses had them, and what a match refuses.
#include "canhil/emulator/match.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/frames/messages.hpp"
#include "support/counter_watch.hpp"
#include "support/error_of.hpp"
#include "support/rtdb_ipc.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class MatchTest : public test::WatchedTest {
 protected:
  SessionOptions options() const {
    SessionOptions o;
    o.messages = frames::MessageSet::load(test::shipped_dbc());
    return o;
  }
  MatchOptions short_match(double half_s) const {
    MatchOptions m;
    m.half_s = half_s;
    return m;
  }
  test::RtdbKeys keys_;
};

TEST_F(MatchTest, InTheSecondHalfTheTeamsChangeEndsAndTheOtherKicksOff) {
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  s.coach.team_game_states = {"our_kickoff", "their_kickoff"};
  const Scenario first = half_scenario(s, 0);
  EXPECT_EQ(first.world.robots, s.world.robots) << "the first half as the file says";
  const Scenario second = half_scenario(s, 1);
  ASSERT_EQ(second.world.robots.size(), s.world.robots.size());
  for (std::size_t r = 0; r < s.world.robots.size(); ++r) {
    EXPECT_DOUBLE_EQ(second.world.robots[r].x_m, -s.world.robots[r].x_m) << r;
    EXPECT_DOUBLE_EQ(second.world.robots[r].y_m, -s.world.robots[r].y_m) << r;
    EXPECT_NEAR(std::fabs(std::remainder(second.world.robots[r].heading_deg - s.world.robots[r].heading_deg, 360.0)),
                180.0, 1e-9)
        << "turned about: " << r;
  }
  EXPECT_FALSE(second.teams[0].attacks_positive_x);
  EXPECT_TRUE(second.teams[1].attacks_positive_x);
  EXPECT_EQ(second.coach.team_game_states, (std::vector<std::string>{"their_kickoff", "our_kickoff"}));
  EXPECT_EQ(half_scenario(s, 2).world.robots, s.world.robots) << "a third half as the first";
  EXPECT_NE(half_seed(7, 0), half_seed(7, 1));
  EXPECT_EQ(half_seed(7, 0), 7u);
}

TEST_F(MatchTest, AGoalInTheSecondHalfCountsForTheTeamNowAttackingThatGoal) {
  Scenario s = half_scenario(load_scenario(shipped_scenario("two_teams.toml")), 1);
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  const double goal_x = s.world.field.length_m / 2 + 0.3;
  session.apply(MoveBall{{goal_x, 0.0, s.world.ball.radius_m}, Eigen::Vector3d::Zero()});
  driver.run_for(100ms);
  ASSERT_NE(session.referee(), nullptr);
  EXPECT_EQ(session.referee()->score(), (std::vector<int>{0, 1})) << "old attacks +x after half time";
}

TEST_F(MatchTest, AMatchPlaysEveryHalfAndItsTallyAddsUp) {
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  std::vector<double> seen;
  const MatchResult r = play_match(s, options(), short_match(8), [&](double played) { seen.push_back(played); });
  EXPECT_FALSE(r.stopped);
  EXPECT_DOUBLE_EQ(r.virtual_s, 16.0);
  ASSERT_EQ(seen.size(), 16u) << "progress after every virtual second";
  EXPECT_DOUBLE_EQ(seen.back(), 16.0);
  ASSERT_EQ(r.teams.size(), 2u);
  int goals = 0;
  double possession = 0;
  for (const TeamTally& t : r.teams) {
    goals += t.goals;
    possession += t.possession_s;
    EXPECT_GT(t.kicks, 0) << "both teams' agents kick";
    EXPECT_LE(t.shots, t.kicks);
    EXPECT_EQ(t.faults, 0u) << "no fault rules";
    EXPECT_EQ(t.ftt_violations, 0u) << "the emulated buses keep FTT";
  }
  EXPECT_EQ(static_cast<std::size_t>(goals), r.goals.size());
  EXPECT_GT(possession, 1.0);
  EXPECT_LE(possession, 16.0 + 1e-9);
  EXPECT_EQ(r.seed, s.seed);
}

TEST_F(MatchTest, OneSeedPlaysOneMatchAnotherSeedAnother) {
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  ASSERT_TRUE(s.vision.any_noise()) << "the shipped scenario's camera is noisy, so seeds matter";
  const MatchResult a = play_match(s, options(), short_match(5));
  const MatchResult again = play_match(s, options(), short_match(5));
  s.seed += 1;
  const MatchResult other = play_match(s, options(), short_match(5));
  for (std::size_t t = 0; t < 2; ++t) {
    EXPECT_EQ(a.teams[t].possession_s, again.teams[t].possession_s) << t;
    EXPECT_EQ(a.teams[t].kicks, again.teams[t].kicks) << t;
    EXPECT_EQ(a.teams[t].shots, again.teams[t].shots) << t;
  }
  EXPECT_NE(a.teams[0].possession_s, other.teams[0].possession_s) << "another seed, another match";
  EXPECT_NE(a.trace_hash, 0u);
  EXPECT_EQ(a.trace_hash, again.trace_hash) << "the same frames at the same times on every bus";
  EXPECT_NE(a.trace_hash, other.trace_hash);
}

TEST_F(MatchTest, FaultsAndFttViolationsCountOnTheBusesThatHadThem) {
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  s.faults.push_back(can_nodes::parse_fault("drop:M4_1:0.2"));
  MatchOptions m = short_match(3);
  m.halves = 1;
  const MatchResult r = play_match(s, options(), m);
  for (const TeamTally& t : r.teams) {
    EXPECT_GT(t.faults, 0u) << "odometry frames dropped on every robot's bus";
    EXPECT_GT(t.ftt_violations, 0u) << "a dropped periodic frame is a missing one";
  }
}

TEST_F(MatchTest, AStopFlagEndsTheMatchWithTheFiguresSoFar) {
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  std::atomic<bool> stop{false};
  const MatchResult r = play_match(
      s, options(), short_match(30),
      [&](double played) {
        if (played >= 2) stop = true;
      },
      &stop);
  EXPECT_TRUE(r.stopped);
  EXPECT_DOUBLE_EQ(r.virtual_s, 2.0);
}

// The reference drivers, seen from outside: which half, on which session,
// and the FTT count a driver reports.
class SeenHalf final : public HalfDriver {
 public:
  struct Log {
    std::vector<std::pair<std::uint64_t, int>> made;  // (match seed, half)
    std::vector<bool> attacks_positive_x;             // the first team's, per half
    std::vector<double> ended_at_s;                   // the session's virtual time when each driver went
  };
  SeenHalf(Session& session, Log& log) : session_(session), log_(log), driver_(session, options()) {}
  ~SeenHalf() override { log_.ended_at_s.push_back(session_.snapshot().time_s); }
  SeenHalf(const SeenHalf&) = delete;
  SeenHalf& operator=(const SeenHalf&) = delete;
  void run_until(Nanos end) override { driver_.run_until(end); }
  Nanos now() const override { return driver_.now(); }
  std::uint64_t ftt_violations(std::size_t) const override { return 7; }
  std::uint64_t trace_hash() const override { return driver_.trace_hash(); }
  std::string trace() const override { return driver_.trace(); }

 private:
  static VirtualOptions options() {
    VirtualOptions o;
    o.record_trace = false;
    return o;
  }
  Session& session_;
  Log& log_;
  VirtualDriver driver_;
};

TEST_F(MatchTest, AGivenDriverPlaysEachHalfOnThatHalfsSessionAndGoesBeforeIt) {
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  SeenHalf::Log log;
  MatchOptions m = short_match(3);
  m.overrides.bit_rate = 0;  // the drivers' order is what counts: the instant bus, cheap under the sanitizers
  m.driver = [&log](Session& session, std::uint64_t seed, int half) {
    log.made.emplace_back(seed, half);
    log.attacks_positive_x.push_back(session.scenario().teams[0].attacks_positive_x);
    return std::make_unique<SeenHalf>(session, log);
  };
  const MatchResult given = play_match(s, options(), m);
  MatchOptions plain = short_match(3);
  plain.overrides.bit_rate = 0;
  const MatchResult reference = play_match(s, options(), plain);
  EXPECT_EQ(log.made, (std::vector<std::pair<std::uint64_t, int>>{{s.seed, 0}, {s.seed, 1}}));
  EXPECT_EQ(log.attacks_positive_x, (std::vector<bool>{true, false})) << "each driver gets its half's session";
  ASSERT_EQ(log.ended_at_s.size(), 2u);
  for (const double t : log.ended_at_s)
    EXPECT_NEAR(t, 3.0, 1e-6) << "each goes at its half's end, its session still there";
  for (std::size_t t = 0; t < 2; ++t) {
    EXPECT_EQ(given.teams[t].ftt_violations, 7u * 5 * 2) << "the driver's count, per robot and half: " << t;
    EXPECT_EQ(given.teams[t].kicks, reference.teams[t].kicks) << "the same play as canhil's own driver: " << t;
    EXPECT_EQ(given.teams[t].possession_s, reference.teams[t].possession_s) << t;
  }
  EXPECT_EQ(given.trace_hash, reference.trace_hash) << "the driver's hash: the same frames";
}

TEST_F(MatchTest, AMatchNeedsTwoTeamsAndItsReferee) {
  const Scenario one = load_scenario(shipped_scenario("one_robot.toml"));
  EXPECT_NE(test::error_of([&] { play_match(one, options(), short_match(1)); }).find("needs two teams"),
            std::string::npos);
  Scenario no_referee = load_scenario(shipped_scenario("two_teams.toml"));
  no_referee.referee.enabled = false;
  EXPECT_NE(test::error_of([&] { play_match(no_referee, options(), short_match(1)); }).find("needs the referee"),
            std::string::npos);
  MatchOptions none = short_match(1);
  none.halves = 0;
  EXPECT_NE(test::error_of([&] {
              play_match(load_scenario(shipped_scenario("two_teams.toml")), options(), none);
            }).find("at least one half"),
            std::string::npos);
}

}  // namespace
}  // namespace canhil::emulator
