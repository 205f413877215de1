// The calibration experiments meet their targets with the default parameters:
// the model checked against reference-figures.md, with tolerances.
#include "canhil/physics/experiments.hpp"

#include <gtest/gtest.h>

namespace canhil::physics {
namespace {

class Experiment : public ::testing::TestWithParam<std::string> {};

TEST_P(Experiment, MeetsEveryTarget) {
  const ExperimentResult r = run_experiment(GetParam(), WorldParams{}, ExperimentOptions{});
  EXPECT_FALSE(r.rows.empty());
  EXPECT_FALSE(r.figures.empty());
  EXPECT_FALSE(r.plots.empty());
  for (const Figure& f : r.figures) EXPECT_TRUE(f.met) << f.name << " = " << f.value << ", target " << f.target;
}

INSTANTIATE_TEST_SUITE_P(All, Experiment, ::testing::ValuesIn(experiment_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param;
                           for (char& c : n) c = c == '-' ? '_' : c;
                           return n;
                         });

TEST(Experiments, DropTestCountsSixBouncesAndRestsAt281) {
  const ExperimentResult r = run_experiment("ball-drop", WorldParams{}, ExperimentOptions{});
  ASSERT_EQ(r.figures.size(), 2u);
  EXPECT_EQ(r.figures[0].value, 6);
  EXPECT_NEAR(r.figures[1].value, 2.81, 0.1);
}

TEST(Experiments, ATargetCanBeMissed) {
  WorldParams p;
  p.ball.restitution = 0.5;  // a dead ball: fewer bounces, earlier rest
  const ExperimentResult r = run_experiment("ball-drop", p, ExperimentOptions{});
  EXPECT_FALSE(r.all_met());
}

TEST(Experiments, UnknownNameIsRefused) {
  EXPECT_THROW(run_experiment("levitate", WorldParams{}, ExperimentOptions{}), SetupError);
}

}  // namespace
}  // namespace canhil::physics
