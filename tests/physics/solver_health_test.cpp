// ODE's own reports through canhil (physics/solver_health.hpp): counted per
// world with their simulation time, the first few kept; an internal error or
// an error stops the world with SolverError instead of aborting the process.
#include "canhil/physics/solver_health.hpp"

#include <gtest/gtest.h>
#include <ode/ode.h>

#include <string>

#include "canhil/physics/world.hpp"
#include "solver_scope.hpp"

namespace canhil::physics {
namespace {

TEST(SolverHealth, AWorldWhoseBallHasNoMassStopsWithODEsOwnWordsInsteadOfAborting) {
  WorldParams p;
  p.ball.mass_kg = 0;  // ODE's dMassCheck fails, then its assertion in dBodySetMass
  try {
    World world(p);
    FAIL() << "a ball of 0 kg was accepted";
  } catch (const SolverError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("ODE internal error"), std::string::npos) << what;
    EXPECT_NE(what.find("dBodySetMass"), std::string::npos) << what;
    EXPECT_NE(what.find("at t = 0.000 s"), std::string::npos) << what;
    EXPECT_EQ(e.report().kind, SolverReportKind::kInternalError);
  }
  // The process goes on, and a sound world is built and stepped after it.
  World sound{WorldParams{}};
  for (int i = 0; i < 100; ++i) sound.step();
  EXPECT_EQ(sound.solver_health().total(), 0u) << sound.solver_health().summary();
}

TEST(SolverHealth, MessagesAreCountedWithTheirTimeAndTheFirstFewKept) {
  SolverHealth health;
  double now = 1.25;
  {
    const detail::SolverScope scope(health, now);
    dMessage(3, "LCP internal error, s <= %d", 0);  // as ODE's solver says it
    now = 2.5;
    for (int i = 0; i < 6; ++i) dMessage(4, "message %d", i);
  }
  EXPECT_EQ(health.messages, 7u);
  EXPECT_EQ(health.internal_errors + health.errors, 0u);
  ASSERT_EQ(health.first.size(), SolverHealth::kKept);
  EXPECT_EQ(health.first[0].text, "LCP internal error, s <= 0");
  EXPECT_EQ(health.first[0].code, 3);
  EXPECT_DOUBLE_EQ(health.first[0].time_s, 1.25);
  EXPECT_DOUBLE_EQ(health.first[1].time_s, 2.5);
  EXPECT_EQ(health.first.back().text, "message 3") << "the first five, not the last";
  EXPECT_NE(health.summary().find("7 solver message(s)"), std::string::npos) << health.summary();
  EXPECT_NE(health.summary().find("first at t = 1.250 s: LCP internal error"), std::string::npos);
  const std::string lines = health.describe("  ");
  EXPECT_NE(lines.find("  physics: 7 solver message(s)"), std::string::npos) << lines;
  EXPECT_NE(lines.find("    t = 2.500 s  ODE message 4: message 0\n"), std::string::npos) << lines;
}

TEST(SolverHealth, AnErrorThrowsOutOfTheCallThatMadeODESayIt) {
  SolverHealth health;
  const double now = 0.5;
  const detail::SolverScope scope(health, now);
  EXPECT_THROW(dError(1, "no memory for %s", "the step"), SolverError);
  EXPECT_THROW(dDebug(2, "assertion failed"), SolverError);
  EXPECT_EQ(health.errors, 1u);
  EXPECT_EQ(health.internal_errors, 1u);
  EXPECT_EQ(health.first.front().text, "no memory for the step");
}

TEST(SolverHealth, RunTotalsAddUpAndKeepTheEarliestReports) {
  SolverHealth a, b;
  a.add({SolverReportKind::kMessage, 1, 0.1, "a"});
  b.add({SolverReportKind::kError, 2, 0.2, "b"});
  b.add({SolverReportKind::kInternalError, 3, 0.3, "c"});
  a.add(b);
  EXPECT_EQ(a.messages, 1u);
  EXPECT_EQ(a.errors, 1u);
  EXPECT_EQ(a.internal_errors, 1u);
  ASSERT_EQ(a.first.size(), 3u);
  EXPECT_EQ(a.first[2].text, "c");
}

}  // namespace
}  // namespace canhil::physics
