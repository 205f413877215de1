// A trace against the analysis of its message set: observations inside their
// bounds pass, one past its bound is named with the frame's time.
#include "canhil/timing/bound_check.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/dbc.hpp"
#include "support/test_paths.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;

class BoundCheck : public ::testing::Test {
 protected:
  BoundCheck() {
    AnalysisConfig c;
    c.what_if = false;
    analysis_ = analyse_bus(read_bus_set(frames::load_dbc(test::shipped_dbc())), c);
  }
  // EC 0's TM at `t`: every synchronous message due, its 1370 us window.
  frames::TimedFrame tm(Nanos t) const {
    std::uint32_t all = 0;
    for (const SyncBound& m : analysis_.sync.messages) all |= 1u << m.index;
    return {set_->tm.encode(frames::Tm{0, all, 1370}), t};
  }
  frames::TimedFrame frame(const char* name, Nanos t) const {
    frames::CanFrame f;
    f.id = set_->codec().find(name)->id();
    f.len = 8;
    return {f, t};
  }
  std::shared_ptr<const frames::MessageSet> set_ = frames::MessageSet::load(test::shipped_dbc());
  BusAnalysis analysis_;
};

TEST_F(BoundCheck, FramesWhereTheAnalysisAllowsThemPass) {
  BoundChecker check(analysis_, set_, 0ns);
  check.add(tm(0ms));
  check.add(frame("M7", 135us));                   // the window opens: the TM (135 us) off the wire
  check.add(frame("M1", 10ms - 1370us));           // the synchronous window's start
  check.add(frame("M9", 10ms - 1370us + 1350us));  // the tenth frame's latest end
  check.add(tm(10ms));
  const BoundReport r = check.finish();
  EXPECT_TRUE(r.ok()) << format_bounds(r);
  EXPECT_EQ(r.frames, 5u);
}

TEST_F(BoundCheck, AnObservationPastItsBoundIsAViolationWithItsTime) {
  BoundChecker check(analysis_, set_, 0ns);
  check.add(tm(0ms));
  check.add(frame("M7", 100us));                   // inside the TM: before the window opened
  check.add(frame("M9", 10ms - 1370us + 1351us));  // 1 us past its latest end
  check.add(tm(10ms + 5us));                       // an EC 5 us long
  const BoundReport r = check.finish();
  ASSERT_EQ(r.violation_count, 3u) << format_bounds(r);
  EXPECT_EQ(r.violations[0].message, "M7");
  EXPECT_EQ(r.violations[0].quantity, Bounded::kAfterOpen);
  EXPECT_EQ(r.violations[0].observed, -35us);
  EXPECT_EQ(r.violations[1].message, "M9");
  EXPECT_EQ(r.violations[1].time, 10ms + 1351us - 1370us);
  EXPECT_EQ(r.violations[1].high, 1350us);
  EXPECT_EQ(r.violations[2].message, "TM");
  EXPECT_EQ(r.violations[2].observed, 10ms + 5us);
  // A tolerance for a real bus's clocks takes the last two, not the first.
  BoundChecker slack(analysis_, set_, 5us);
  slack.add(tm(0ms));
  slack.add(frame("M7", 100us));
  slack.add(frame("M9", 10ms - 1370us + 1351us));
  slack.add(tm(10ms + 5us));
  EXPECT_EQ(slack.finish().violation_count, 1u);
  EXPECT_NE(format_bounds(r).find("OUTSIDE"), std::string::npos);
}

}  // namespace
}  // namespace canhil::timing
