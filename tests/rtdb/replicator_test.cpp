// The replicator through a Database: canhil's linked RTDB (delay, loss, seed)
// and a team's library loaded at run time (the stand-in: its put counters
// show the copies went through it). Own System V keys, nothing left behind.
#include "canhil/rtdb/replicator.hpp"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"
#include "support/team_rtdb.hpp"

namespace canhil::rtdb {
namespace {

using namespace std::chrono_literals;

class ReplicatorTest : public ::testing::Test {
 protected:
  void SetUp() override { setenv("AGENT", "1", 1); }
  void TearDown() override { EXPECT_EQ(keys_.leftovers(), "") << "segments left behind"; }
  test::RtdbKeys keys_;
};

TEST_F(ReplicatorTest, DelayAndLossThroughTheBuiltin) {
  const auto db = open_builtin(Scope::kAllAgents);
  ReplicatorConfig cfg;
  cfg.delay = 300ms;
  Replicator rep(*db, cfg);
  const RobotWS w{0, 0, 0, 1, 42};
  DB_put_in(CAMBADA_3, CAMBADA_3, ROBOT_WS, const_cast<RobotWS*>(&w), 0);
  rep.cycle(0ms);
  RobotWS seen{};
  DB_get_from(CAMBADA_4, CAMBADA_3, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 0u) << "still in flight";
  EXPECT_GT(rep.in_flight(), 0u);
  rep.deliver(299ms);
  DB_get_from(CAMBADA_4, CAMBADA_3, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 0u);
  rep.deliver(300ms);
  const int age = DB_get_from(CAMBADA_4, CAMBADA_3, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 42u) << "arrived after the delay, between two cycles";
  EXPECT_GE(age, 300) << "aged by its time in flight";
  EXPECT_EQ(rep.in_flight(), 0u);
  EXPECT_EQ(rep.stats().cycles, 1u) << "deliver() copies nothing new";

  ReplicatorConfig lossy;
  lossy.loss = 0.5;
  lossy.seed = 9;
  Replicator r2(*db, lossy);
  for (int i = 0; i < 200; ++i) r2.cycle(std::chrono::milliseconds(100 * i));
  const double lost = static_cast<double>(r2.stats().lost) / static_cast<double>(r2.stats().lost + r2.stats().copied);
  EXPECT_NEAR(lost, 0.5, 0.05);
  Replicator r3(*db, lossy);
  for (int i = 0; i < 200; ++i) r3.cycle(std::chrono::milliseconds(100 * i));
  EXPECT_EQ(r3.stats().lost, r2.stats().lost) << "seeded: the same losses";
}

TEST_F(ReplicatorTest, RunCyclesOnItsPeriodAndDeliversEachDelayedCopyWhenDue) {
  // A fake clock that sleeping moves: what run() asks to sleep until is when
  // it next acts. Cycles every 100 ms; copies 30 ms in flight arrive at 30 ms
  // past each cycle, not at the next cycle.
  const auto db = open_builtin(Scope::kAllAgents);
  ReplicatorConfig cfg;
  cfg.delay = 30ms;
  Replicator rep(*db, cfg);
  RobotWS w{0, 0, 0, 1, 7};
  DB_put_in(CAMBADA_3, CAMBADA_3, ROBOT_WS, &w, 0);
  std::chrono::nanoseconds t = 1000ms;
  std::vector<std::chrono::nanoseconds> woken;
  std::vector<unsigned> seen_at_wake;
  std::atomic<bool> stop{false};
  rep.run([&] { return t; },
          [&](std::chrono::nanoseconds until) {
            RobotWS seen{};
            DB_get_from(CAMBADA_4, CAMBADA_3, ROBOT_WS, &seen);
            seen_at_wake.push_back(seen.frame);
            woken.push_back(until);
            t = until;
            if (woken.size() == 5) stop = true;
          },
          stop);
  EXPECT_EQ(woken, (std::vector<std::chrono::nanoseconds>{1030ms, 1100ms, 1130ms, 1200ms, 1230ms}));
  EXPECT_EQ(seen_at_wake.front(), 0u) << "in flight after the first cycle";
  EXPECT_EQ(seen_at_wake[1], 7u) << "delivered at 1030 ms";
  EXPECT_EQ(rep.stats().cycles, 3u);

  // A stall of 350 ms skips the cycles it missed.
  ReplicatorConfig plain;
  Replicator steady(*db, plain);
  t = 0ms;
  woken.clear();
  std::atomic<bool> stop2{false};
  steady.run([&] { return t; },
             [&](std::chrono::nanoseconds until) {
               woken.push_back(until);
               t = woken.size() == 1 ? until + 350ms : until;
               if (woken.size() == 3) stop2 = true;
             },
             stop2);
  EXPECT_EQ(woken, (std::vector<std::chrono::nanoseconds>{100ms, 500ms, 600ms}));
  EXPECT_EQ(steady.stats().cycles, 3u) << "at 0, 450 and 500 ms";
}

TEST_F(ReplicatorTest, APeriodDelayOrLossOutOfRangeIsRefused) {
  const auto db = open_builtin(Scope::kAllAgents);
  ReplicatorConfig bad;
  bad.period = 0ms;
  EXPECT_THROW(Replicator(*db, bad), SetupError);
  bad = {};
  bad.delay = -1ms;
  EXPECT_THROW(Replicator(*db, bad), SetupError);
  bad = {};
  bad.loss = 1.5;
  EXPECT_THROW(Replicator(*db, bad), SetupError);
}

TEST_F(ReplicatorTest, ThroughTheTeamsLibrary) {
  const test::TeamFiles f = test::write_team_files("replicator_team");
  const auto db =
      open_library(test::team_rtdb_library(), ItemTable::from_files(f.user_h, f.ini), Scope::kAllAgents, f.ini);
  std::array<unsigned char, 20> ws{};
  ws[0] = 9;
  db->put(test::kRobot1, test::kRobot1, test::kRobotWs, std::as_bytes(std::span(ws)), 150);
  Replicator rep(*db, {});
  rep.cycle(0ms);
  // Robot 1's ROBOT_WS reached the base station and robot 2; the base
  // station's COACH_INFO and robot 2's ROBOT_WS were never written.
  EXPECT_EQ(rep.stats().copied, 2u);
  EXPECT_EQ(rep.stats().never_written, 2u);
  EXPECT_EQ(test::standin_put_count(test::kBaseStation, test::kRobotWs), 1) << "written through the team's library";
  EXPECT_EQ(test::standin_put_count(test::kRobot2, test::kRobotWs), 1);
  EXPECT_EQ(test::standin_put_count(test::kRobot1, test::kCoachInfo), 0);
  std::array<unsigned char, 20> seen{};
  const auto age = db->get(test::kRobot2, test::kRobot1, test::kRobotWs, std::as_writable_bytes(std::span(seen)));
  ASSERT_TRUE(age.has_value());
  EXPECT_GE(*age, 150) << "the age it had when read";
  EXPECT_EQ(seen[0], 9);
}

TEST_F(ReplicatorTest, NeedsEveryAgentsDatabase) {
  const auto db = open_builtin(Scope::kOneAgent);
  try {
    Replicator rep(*db, {});
    FAIL() << "a one-agent database was accepted";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("open " + db->library() + " for every agent (Scope::kAllAgents)"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace canhil::rtdb
