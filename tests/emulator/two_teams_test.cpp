// Two teams on one computer, in virtual time: both teams' loops closed on
// their own RTDB sets (both use agents 1..5 and never see each other's
// items), the second team attacks -x and scores there, after a goal the team
// that conceded takes its kick-off, a ball into a goal during a restart's
// pause is no goal, and a [[teams]] file's mistakes are named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"
#include "support/counter_watch.hpp"
#include "support/error_of.hpp"
#include "support/rtdb_ipc.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class TwoTeams : public test::WatchedTest {
 protected:
  SessionOptions options() const {
    SessionOptions o;
    o.messages = frames::MessageSet::load(test::shipped_dbc());
    return o;
  }
  test::RtdbKeys keys_;
};

TEST_F(TwoTeams, BothTeamsLoopsCloseOnTheirOwnRtdbSets) {
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  ASSERT_EQ(s.teams.size(), 2u);
  ASSERT_EQ(s.robot_count(), 10u);
  EXPECT_EQ(s.agents, (std::vector<int>{1, 2, 3, 4, 5, 1, 2, 3, 4, 5})) << "each team numbers its own";
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  driver.run_for(2s);
  for (std::size_t r = 0; r < 10; ++r) {  // every agent acts: drives to the ball, or turns to find it
    const auto& start = s.world.robots[r];
    const auto pose = session.world().robot(r).pose();
    const double moved = std::hypot(pose.x_m - start.x_m, pose.y_m - start.y_m);
    const double turned = std::fabs(std::remainder(pose.heading_rad - start.heading_deg * M_PI / 180, 2 * M_PI));
    EXPECT_TRUE(moved > 0.2 || turned > 0.3) << "robot " << r << " moved " << moved << " m, turned " << turned;
  }
  // Each team's agent 1 reads its own robot's odometry from its own set.
  ASSERT_EQ(DB_init_all(0), 0);
  ASSERT_EQ(DB_init_all(1), 0);
  CMD_Pos first{}, second{};
  ASSERT_GE(DB_get_from(CAMBADA_1, CAMBADA_1, CMD_POS, &first), 0);
  ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_1, CAMBADA_1, CMD_POS, &second), 0);
  const auto a = session.world().robot(0).pose();
  const auto b = session.world().robot(5).pose();
  EXPECT_NEAR(first.px, a.x_m, 0.3);
  EXPECT_NEAR(second.px, b.x_m, 0.3);
  EXPECT_GT(std::fabs(first.px - second.px), 0.5) << "two robots, two databases";
  // A shared item of the second team's agent 1 reaches its team mates only.
  RobotWS mark{0, 0, 0, 1, 777};
  ASSERT_GT(DB_put_in(N_AGENTS + CAMBADA_1, CAMBADA_1, ROBOT_WS, &mark, 0), 0);
  driver.run_for(500ms);  // replicator cycles
  RobotWS seen{};
  ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen), 0);
  EXPECT_EQ(seen.frame, 777u) << "its team mate has it";
  ASSERT_GE(DB_get_from(CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen), 0);
  EXPECT_NE(seen.frame, 777u) << "the other team's agent 2 must not";
  DB_free_all(1);
  DB_free_all(0);
}

TEST_F(TwoTeams, TheSecondTeamAttacksMinusXAndScoresThere) {
  Scenario s = parse_scenario(R"(
[run]
duration_s = 8
[ball_start]
x_m = -3.0
y_m = 0.0
z_m = 0.11
[[teams]]
name = "far"
[[teams.robots]]
x_m = 8.0
y_m = 5.5
heading_deg = 90.0
[[teams]]
name = "near"
attacks = "-x"
[[teams.robots]]
x_m = -1.5
y_m = 0.0
heading_deg = 90.0
)",
                              "inline.toml");
  EXPECT_FALSE(s.teams[1].attacks_positive_x);
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  driver.run_for(8s);
  ASSERT_FALSE(session.goals().empty()) << "ball at " << session.world().ball_position().transpose();
  EXPECT_FALSE(session.goals().front().positive_x) << "in the -x goal, the one the second team attacks";
  // The referee (on with two teams): the goal is near's, far kicks off from the centre.
  ASSERT_NE(session.referee(), nullptr);
  EXPECT_EQ(session.referee()->score()[1], 1);
  const RefereeCall& call = session.referee()->calls().front();
  EXPECT_EQ(call.restart, Restart::kKickoff);
  EXPECT_EQ(call.team, 0u);
  EXPECT_EQ(call.time, session.goals().front().time);
}

TEST_F(TwoTeams, ABallKickedOutComesBackOnTheLineForTheOtherTeamTheSameTwice) {
  const auto run = [this] {
    Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
    s.world.ball_start = {3.0, 5.5, 0.11};
    Session session(plan_run(s, options()));
    session.apply(MoveBall{{3.0, 5.5, 0.11}, {0.0, 3.0, 0.0}});  // rolling out over the +y touch line
    std::vector<std::string> states;
    session.on_coach_change([&](const CoachState& c) { states.push_back(c.state_of(0) + "/" + c.state_of(1)); });
    VirtualDriver driver(session, {});
    const auto watching = counters.watch_session(session);
    driver.run_for(4s);
    EXPECT_NE(session.referee(), nullptr);
    const auto& calls = session.referee()->calls();
    EXPECT_FALSE(calls.empty());
    if (calls.empty()) return std::string();
    EXPECT_EQ(calls.front().restart, Restart::kThrowIn) << calls.front().text;
    EXPECT_NEAR(calls.front().spot.y(), 6.0, 1e-9);
    EXPECT_NEAR(calls.front().spot.x(), 3.0, 0.3);
    EXPECT_FALSE(states.empty());
    if (!states.empty()) {
      EXPECT_NE(states.front().find("throwin"), std::string::npos) << states.front();
    }
    std::string all;
    for (const auto& c : calls) all += std::to_string(c.time.count()) + " " + c.text + "\n";
    for (const auto& st : states) all += st + "\n";
    char pose[64];
    std::snprintf(pose, sizeof pose, "%.9f %.9f", session.world().ball_position().x(),
                  session.world().ball_position().y());
    return all + pose;
  };
  const std::string first = run();
  EXPECT_EQ(run(), first) << "one seed, one match";
}

TEST_F(TwoTeams, ARestartSendsRobotsOffTheSpotNeverIntoEachOtherAndIntoTheWorldLog) {
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  s.world.ball_start = {3.0, 5.5, 0.11};
  s.world.robots[0] = {2.45, 5.5, -90};  // both within 1 m of where the ball goes out,
  s.world.robots[1] = {3.55, 5.5, -90};  // both stepping back towards -x ...
  s.world.robots[2] = {1.85, 5.5, -90};  // ... where this one stands
  SessionOptions o = options();
  o.world_log_period = std::chrono::milliseconds(50);
  Session session(plan_run(s, o));
  session.apply(MoveBall{{3.0, 5.5, 0.11}, {0.0, 3.0, 0.0}});
  std::vector<Eigen::Vector2d> at_call;
  Eigen::Vector2d spot = Eigen::Vector2d::Zero();
  session.on_referee_call([&](const RefereeCall& c) {
    if (!at_call.empty()) return;
    spot = c.spot;
    for (std::size_t r = 0; r < s.robot_count(); ++r) {
      const auto p = session.world().robot(r).pose();
      at_call.emplace_back(p.x_m, p.y_m);
    }
  });
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  driver.run_for(1s);
  ASSERT_FALSE(at_call.empty()) << "the ball went out";
  const double radius = s.world.robot.body_radius_m;
  for (std::size_t r = 0; r < at_call.size(); ++r) {
    EXPECT_GE((at_call[r] - spot).norm(), 1.0 - 1e-9) << "robot " << r << " keeps its distance";
    for (std::size_t o2 = r + 1; o2 < at_call.size(); ++o2) {
      EXPECT_GE((at_call[r] - at_call[o2]).norm(), 2 * radius) << "robots " << r << " and " << o2 << " overlap";
    }
  }
  const std::string& log = session.world_log();
  const auto line = log.find("\n#referee,");
  ASSERT_NE(line, std::string::npos) << "the call is in the world log";
  EXPECT_NE(log.find(",throwin,", line), std::string::npos) << log.substr(line, 80);
  EXPECT_NE(log.find(",0,0\n", line), std::string::npos) << "with the score";
}

TEST_F(TwoTeams, AfterAKickOffEveryReferenceAgentsOdometryKnowsWhereTheRefereePutItsRobot) {
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  driver.run_for(3s);  // the robots drive off their places
  ASSERT_EQ(session.referee_placements(0), 0u);
  // A goal for the first team: the ball rolled into the goal it attacks.
  session.apply(MoveBall{{s.world.field.length_m / 2 - 0.3, 0.7, 0.11}, {3.0, 0.0, 0.0}});  // past the keeper
  std::vector<kinematics::Pose> placed;
  session.on_referee_call([&](const RefereeCall& c) {
    if (c.restart != Restart::kKickoff || !placed.empty()) return;
    for (std::size_t r = 0; r < s.robot_count(); ++r) placed.push_back(session.world().robot(r).pose());
  });
  driver.run_for(500ms);  // the call, then a few of the handlers' cycles (the pause holds the agents still)
  ASSERT_EQ(placed.size(), s.robot_count()) << "a kick-off after the goal";
  ASSERT_EQ(DB_init_all(0), 0);
  ASSERT_EQ(DB_init_all(1), 0);
  for (std::size_t r = 0; r < s.robot_count(); ++r) {
    EXPECT_EQ(session.referee_placements(r), 1u) << r;
    const int space = (r < 5 ? 0 : N_AGENTS) + s.agents[r];
    CMD_Pos odometry{};
    ASSERT_GE(DB_get_from(space, s.agents[r], CMD_POS, &odometry), 0) << r;
    EXPECT_NEAR(odometry.px, s.world.robots[r].x_m, 0.05)
        << "robot " << r << " back at its place, and its odometry too";
    EXPECT_NEAR(odometry.py, s.world.robots[r].y_m, 0.05) << r;
    EXPECT_NEAR(placed[r].x_m, s.world.robots[r].x_m, 1e-6) << r;
  }
  DB_free_all(1);
  DB_free_all(0);
}

TEST_F(TwoTeams, AfterAGoalTheTeamThatConcededTakesItsKickOff) {
  // The reference agents of both teams used to drive at the ball on "start",
  // clamp it between new's and old's front robots and kick into each other:
  // the kick-off was never taken, the referee dropped the ball 12 s later.
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  s.vision = {};  // an exact camera: one game
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  session.apply(MoveBall{{s.world.field.length_m / 2 - 0.3, 0.7, 0.11}, {3.0, 0.0, 0.0}});  // new scores
  driver.run_for(500ms);
  ASSERT_NE(session.referee(), nullptr);
  ASSERT_EQ(session.referee()->calls().size(), 1u);
  const RefereeCall kickoff = session.referee()->calls().front();
  ASSERT_EQ(kickoff.restart, Restart::kKickoff);
  ASSERT_EQ(kickoff.team, 1u) << "old conceded";
  // From "start" on: old's robots alone at the ball until it is in play; it leaves the centre circle.
  const Nanos start = kickoff.time + from_seconds(s.referee.restart_pause_s);
  double farthest = 0;
  double new_nearest = 1e9;  // new's robots to the ball, until it is in play
  session.on_step([&](Nanos) {
    const auto& w = session.world();
    const Eigen::Vector2d ball = w.ball_position().head<2>();
    farthest = std::max(farthest, ball.norm());
    if (farthest > 0.5) return;
    for (std::size_t r = 0; r < 5; ++r) {
      const auto p = w.robot(r).pose();
      new_nearest = std::min(new_nearest, (Eigen::Vector2d(p.x_m, p.y_m) - ball).norm());
    }
  });
  driver.run_until(start + 8s);
  session.on_step(nullptr);
  EXPECT_GT(farthest, 2.0) << "the kick-off was taken: the ball left the centre circle";
  EXPECT_GT(new_nearest, 1.0) << "new kept off the ball until old had played it";
  for (const RefereeCall& c : session.referee()->calls()) {
    EXPECT_NE(c.restart, Restart::kDroppedBall) << c.text;
  }
}

TEST_F(TwoTeams, ABallIntoAGoalDuringARestartsPauseIsNoGoalTheRestartIsTakenAgain) {
  Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  s.vision = {};
  Session session(plan_run(s, options()));
  VirtualDriver driver(session, {});
  const auto watching = counters.watch_session(session);
  const double line = s.world.field.length_m / 2;
  session.apply(MoveBall{{line - 0.4, -3.0, 0.11}, {3.0, 0.0, 0.0}});  // out beside the goal, untouched
  driver.run_for(500ms);
  ASSERT_NE(session.referee(), nullptr);
  ASSERT_EQ(session.referee()->calls().size(), 1u);
  const RefereeCall kick = session.referee()->calls().front();
  ASSERT_EQ(kick.restart, Restart::kGoalKick) << kick.text;
  // 1.3 s into the pause the ball goes into the +x goal (a team's agent that plays in every state but stop).
  driver.run_until(kick.time + 1300ms);
  session.apply(MoveBall{{line - 0.3, 0.3, 0.11}, {3.0, 0.0, 0.0}});
  driver.run_for(300ms);
  EXPECT_TRUE(session.goals().empty()) << "not in play: no goal";
  EXPECT_EQ(session.referee()->score(), (std::vector<int>{0, 0}));
  ASSERT_EQ(session.referee()->calls().size(), 2u);
  const RefereeCall& again = session.referee()->calls().back();
  EXPECT_EQ(again.restart, Restart::kGoalKick) << again.text;
  EXPECT_EQ(again.team, kick.team);
  EXPECT_EQ(again.spot, kick.spot);
  const Eigen::Vector3d ball = session.world().ball_position();
  EXPECT_NEAR(ball.x(), kick.spot.x(), 1e-3) << "back on its spot";
  EXPECT_NEAR(ball.y(), kick.spot.y(), 1e-3);
  EXPECT_EQ(session.coach().state_of(*kick.team), "our_goalkick");
}

TEST_F(TwoTeams, TheWorldLogSaysWhoPlaysForWhomAndOneTeamsLogDoesNot) {
  SessionOptions o = options();
  o.world_log_period = std::chrono::milliseconds(50);
  const Scenario s = load_scenario(shipped_scenario("two_teams.toml"));
  const Session two(plan_run(s, o));
  const std::string& log = two.world_log();
  const auto header_end = log.find('\n');
  ASSERT_NE(header_end, std::string::npos);
  std::string expected = "#team,0,new,+x\n#team,1,old,-x\n";
  for (std::size_t r = 0; r < 10; ++r) {
    expected += "#robot," + std::to_string(r) + "," + std::to_string(r / 5) + "," + std::to_string(r % 5 + 1) +
                ",vcan" + std::to_string(r) + "\n";
  }
  EXPECT_EQ(log.substr(header_end + 1, expected.size()), expected) << "right after the header";
  const Session one(plan_run(load_scenario(shipped_scenario("five_robots.toml")), o));
  EXPECT_EQ(one.world_log().find("\n#"), std::string::npos) << "one team's world log as it always was";
}

TEST_F(TwoTeams, MistakesInTeamsAreNamedWithTheirLine) {
  const auto error = [](const std::string& text) { return test::error_of([&] { parse_scenario(text, "t.toml"); }); };
  const std::string robot = "[[teams.robots]]\nx_m = -2.0\n";
  EXPECT_NE(error("[[robots]]\nx_m = 1.0\n[[teams]]\n" + robot).find("t.toml:1: robots: with [[teams]]"),
            std::string::npos)
      << error("[[robots]]\nx_m = 1.0\n[[teams]]\n" + robot);
  EXPECT_NE(error("[[teams]]\nname = \"a\"\n").find("a team needs its robots"), std::string::npos);
  EXPECT_NE(error("[[teams]]\nattacks = \"up\"\n" + robot).find("t.toml:2: teams.attacks"), std::string::npos);
  EXPECT_NE(error("[[teams]]\n" + robot + "[[teams]]\n" + robot + "[[teams]]\n" + robot).find("two teams at most"),
            std::string::npos);
  EXPECT_NE(error("[[teams]]\nattacks = \"+x\"\n" + robot + "[[teams]]\nattacks = \"+x\"\n" + robot)
                .find("both teams attack the +x goal"),
            std::string::npos);
  EXPECT_NE(error("[[teams]]\n" + robot + "agent = 2\n" + robot + "agent = 2\n").find("agent 2 is given to two robots"),
            std::string::npos);
  EXPECT_NE(error("[[teams]]\n" + robot + "interface = \"can0\"\n[[teams]]\n" + robot + "interface = \"can0\"\n")
                .find("interface can0 is given to two robots"),
            std::string::npos);
  EXPECT_NE(error("[run]\nagents = [1]\n[[teams]]\n" + robot).find("run.agents: unknown field"), std::string::npos);
  EXPECT_NE(error("[[teams]]\n" + robot + "speed = 3\n").find("teams.robots.speed: unknown field"), std::string::npos);
  std::string seven = "[[teams]]\n";
  for (int k = 0; k < 7; ++k) seven += robot;
  EXPECT_NE(error(seven).find("at most 6 robots"), std::string::npos);
  // Two teams of six: twelve robots, agents 1..6 each.
  std::string twelve = "[[teams]]\n";
  for (int k = 0; k < 6; ++k) twelve += robot;
  twelve += "[[teams]]\n";
  for (int k = 0; k < 6; ++k) twelve += robot;
  const Scenario s = parse_scenario(twelve, "t.toml");
  EXPECT_EQ(s.robot_count(), 12u);
  EXPECT_EQ(s.agents[11], 6);
  EXPECT_EQ(s.interfaces[11], "vcan11");
  EXPECT_EQ(s.team_of(6), 1u);
  EXPECT_FALSE(s.teams[1].attacks_positive_x) << "the second attacks -x unless told";
}

TEST_F(TwoTeams, OneTeamScenariosAreOneImplicitTeam) {
  const Scenario s = load_scenario(shipped_scenario("five_robots.toml"));
  ASSERT_EQ(s.teams.size(), 1u);
  EXPECT_EQ(s.teams[0].name, "canhil");
  EXPECT_TRUE(s.teams[0].attacks_positive_x);
  EXPECT_EQ(s.teams[0].robots, 5u);
}

TEST_F(TwoTeams, EachTeamHasItsOwnGameState) {
  Scenario s = parse_scenario(
      "[coach]\ngame_state = \"stop\"\n[[teams]]\ngame_state = \"our_kickoff\"\n[[teams.robots]]\nx_m = -2.0\n"
      "[[teams]]\n[[teams.robots]]\nx_m = 2.0\n",
      "t.toml");
  EXPECT_EQ(s.coach.state_of(0), "our_kickoff");
  EXPECT_EQ(s.coach.state_of(1), "stop") << "[coach]'s where the team says nothing";
  Session session(plan_run(s, options()));
  EXPECT_EQ(session.team_coach(1).game_state, "stop");
  EXPECT_EQ(session.team_coach(1).players.size(), 1u);
  session.apply(SetCoach{"their_kickoff", std::nullopt, std::nullopt, std::nullopt, 1});
  session.before_step();
  EXPECT_EQ(session.coach().state_of(1), "their_kickoff");
  EXPECT_EQ(session.coach().state_of(0), "our_kickoff");
  EXPECT_THROW(session.apply(SetCoach{"stop", std::nullopt, std::nullopt, std::nullopt, 2}), SetupError);
}

}  // namespace
}  // namespace canhil::emulator
