// The line `canhil bench --part match` fits to a run's world steps, and the
// halves' timings added up: checked against values worked by hand.
#include "canhil/emulator/step_timing.hpp"

#include <gtest/gtest.h>

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

TEST(PhysicsTiming, TheSlopeIsTheCostOfEachContactPointMore) {
  PhysicsTiming t;
  // Steps on y = 3 us + 2 us a contact point: 10 -> 23 us, 12 -> 27, 15 -> 33.
  t.add(10, 23us);
  t.add(12, 27us);
  t.add(15, 33us);
  EXPECT_EQ(t.steps, 3U);
  EXPECT_EQ(t.cpu, 83us);
  EXPECT_NEAR(t.contacts_per_step(), 37.0 / 3, 1e-12);
  EXPECT_NEAR(t.us_per_contact(), 2.0, 1e-9);
  // Off the line: (0, 1), (1, 2), (2, 6): slope (3*14 - 3*9) / (3*5 - 9) = 2.5.
  PhysicsTiming scattered;
  scattered.add(0, 1us);
  scattered.add(1, 2us);
  scattered.add(2, 6us);
  EXPECT_NEAR(scattered.us_per_contact(), 2.5, 1e-9);
}

TEST(PhysicsTiming, RunsAddUpAsOneAndNoSpreadGivesNoSlope) {
  PhysicsTiming first;
  first.add(10, 23us);
  PhysicsTiming second;
  second.add(12, 27us);
  second.add(15, 33us);
  first += second;
  EXPECT_EQ(first.steps, 3U);
  EXPECT_NEAR(first.us_per_contact(), 2.0, 1e-9);
  PhysicsTiming flat;
  flat.add(16, 20us);
  flat.add(16, 30us);
  EXPECT_EQ(flat.us_per_contact(), 0) << "every step made as many contact points: no line";
  EXPECT_EQ(PhysicsTiming{}.contacts_per_step(), 0);
}

TEST(StepTiming, HalvesAddUpTheirPhysicsAndTheirVision) {
  StepTiming first;
  first.physics.add(10, 23us);
  first.vision = 5us;
  StepTiming second;
  second.physics.add(12, 27us);
  second.vision = 7us;
  first += second;
  EXPECT_EQ(first.physics.steps, 2U);
  EXPECT_EQ(first.physics.cpu, 50us);
  EXPECT_EQ(first.vision, 12us);
}

}  // namespace
}  // namespace canhil::emulator
