// canhil timing's analysis: a clean trace of the emulated nodes has no
// violation; each fault put into it is found, and nothing else.
#include "canhil/timing/analysis.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/wire.hpp"
#include "support/node_rig.hpp"
#include "support/test_paths.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;

// 3 s of one robot's bus in virtual time, the laptop sending M6 in its slots,
// plus the laptop's own frames (a listener hears everyone but itself). The
// nodes drive a fake robot: timing needs the bus, not the physics.
std::vector<frames::TimedFrame> clean_trace() {
  test::NodeRig rig;
  rig.laptop.m6_1 = frames::M6_1{0, 0.4};
  auto listener = rig.bus.attach("listener", 1 << 20);
  rig.run.run_until(3s);
  std::vector<frames::TimedFrame> out;
  while (auto f = listener->receive()) out.push_back(*f);
  return out;
}

class Timing : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    set_ = frames::MessageSet::load(test::shipped_dbc());
    trace_ = new std::vector<frames::TimedFrame>(clean_trace());
  }
  static void TearDownTestSuite() {
    delete trace_;
    set_.reset();
  }
  static TimingReport analyse(const std::vector<frames::TimedFrame>& trace) {
    TimingAnalyzer a(set_, TimingConfig{});
    for (const auto& f : trace) a.add(f);
    return a.finish();
  }
  static std::size_t nth(std::uint32_t id, int n) {
    int seen = 0;
    for (std::size_t i = 0; i < trace_->size(); ++i) {
      if ((*trace_)[i].frame.id == id && seen++ == n) return i;
    }
    return trace_->size();
  }
  static inline std::shared_ptr<const frames::MessageSet> set_;
  static inline std::vector<frames::TimedFrame>* trace_ = nullptr;
};

TEST_F(Timing, TheEmulatorsTraceIsClean) {
  const TimingReport r = analyse(*trace_);
  EXPECT_TRUE(r.ok()) << format_table(r);
  EXPECT_GT(r.frames, 1500u);
  EXPECT_EQ(r.unknown, 0u);
  for (const auto& m : r.messages) {
    if (m.name == "TM") {
      EXPECT_EQ(m.count, 301u);
      EXPECT_EQ(m.mean, 10ms);
      EXPECT_EQ(m.p99, Nanos{0});
    }
    if (m.name == "M3_1") {
      EXPECT_EQ(m.count, 300u);
    }
    if (m.name == "M4_1") {
      EXPECT_EQ(m.count, 60u);
    }
  }
  EXPECT_NEAR(r.bus_load, 0.075, 0.01) << "about 7 % of 1 Mbit/s";
}

TEST_F(Timing, BusLoadCountsEveryBitWithStuffing) {
  std::uint64_t bits = 0;
  for (const auto& f : *trace_) bits += frames::frame_bits(f.frame);
  const TimingReport r = analyse(*trace_);
  EXPECT_EQ(r.bits, bits);
  const double seconds = std::chrono::duration<double>(trace_->back().time - trace_->front().time).count();
  EXPECT_DOUBLE_EQ(r.bus_load, static_cast<double>(bits) / (seconds * 1e6));
}

TEST_F(Timing, AMissingFrameIsFound) {
  auto t = *trace_;
  const std::size_t i = nth(0x112, 100);
  const Nanos next = t[nth(0x112, 101)].time;  // the gap shows when the next one comes
  t.erase(t.begin() + static_cast<long>(i));
  const TimingReport r = analyse(t);
  ASSERT_EQ(r.violation_count, 1u) << format_table(r);
  EXPECT_EQ(r.violations[0].message, "M3_2");
  EXPECT_EQ(r.violations[0].kind, ViolationKind::kMissing);
  EXPECT_EQ(r.violations[0].time, next);
}

TEST_F(Timing, ASynchronousFrameOutsideItsWindowIsFound) {
  auto t = *trace_;
  const std::size_t i = nth(0x141, 10);  // an M8
  t[i].time -= 1600us;                   // before the window, still in its EC
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  const TimingReport r = analyse(t);
  ASSERT_EQ(r.violation_count, 1u) << format_table(r);
  EXPECT_EQ(r.violations[0].message, "M8");
  EXPECT_EQ(r.violations[0].kind, ViolationKind::kOutsideWindow);
}

TEST_F(Timing, ASporadicFrameTooSoonIsFound) {
  auto t = *trace_;
  std::size_t last_m2 = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i].frame.id == 0x200) last_m2 = i;
  }
  // A copy of the last M2, 300 ms later, just after that EC's TM.
  const Nanos at = t[last_m2].time + 300ms;
  frames::TimedFrame extra = t[last_m2];
  extra.time = at;
  t.push_back(extra);
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  const TimingReport r = analyse(t);
  ASSERT_EQ(r.violation_count, 1u) << format_table(r);
  EXPECT_EQ(r.violations[0].message, "M2");
  EXPECT_EQ(r.violations[0].kind, ViolationKind::kTooSoon);
}

TEST_F(Timing, ALateFrameIsFoundAndOnlyThroughWhatItBreaks) {
  auto t = *trace_;
  const std::size_t i = nth(0x121, 20);  // an M4_1, 6 ms late: past its period's tolerance
  const Nanos when = t[i].time + 6ms;
  t[i].time = when;
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  const TimingReport r = analyse(t);
  ASSERT_GE(r.violation_count, 1u);
  bool late = false;
  for (const Violation& v : r.violations) {
    EXPECT_EQ(v.message, "M4_1") << format_table(r);
    EXPECT_EQ(v.time, when);
    late = late || v.kind == ViolationKind::kLate;
  }
  EXPECT_TRUE(late) << "reported late (and, landing in the next EC, unscheduled there)";
}

TEST_F(Timing, AnUnscheduledDuplicateIsFound) {
  auto t = *trace_;
  const std::size_t i = nth(0x100, 5);  // an M1, sent again in the next EC's window
  frames::TimedFrame again = t[i];
  again.time += 10ms;
  t.push_back(again);
  std::stable_sort(t.begin(), t.end(), [](const auto& a, const auto& b) { return a.time < b.time; });
  const TimingReport r = analyse(t);
  bool unscheduled = false;
  for (const Violation& v : r.violations) unscheduled = unscheduled || v.kind == ViolationKind::kUnscheduled;
  EXPECT_TRUE(unscheduled) << format_table(r);
}

bool has_problem(const TimingReport& r, CaptureProblem p) {
  for (const auto& [kind, text] : r.capture_problems) {
    if (kind == p) return true;
  }
  return false;
}

TEST_F(Timing, ACleanCaptureHasNoCaptureProblem) {
  const TimingReport r = analyse(*trace_);
  EXPECT_TRUE(r.capture_ok()) << format_table(r);
  EXPECT_EQ(r.longest_period, 50ms);  // M4_1, M4_2, M8
}

TEST_F(Timing, AnEmptyCaptureIsAProblemNotAPass) {
  const TimingReport r = analyse({});
  EXPECT_TRUE(r.ok());           // nothing violated ...
  EXPECT_FALSE(r.capture_ok());  // ... because nothing was there
  EXPECT_TRUE(has_problem(r, CaptureProblem::kNoFrames));
  EXPECT_NE(format_table(r).find("capture problem: the capture has no frames"), std::string::npos);
  EXPECT_NE(format_json(r).find("\"capture_ok\":false"), std::string::npos);
}

TEST_F(Timing, FramesWithoutATriggerMessageAreAProblem) {
  std::vector<frames::TimedFrame> no_tm;
  for (const auto& f : *trace_) {
    if (f.frame.id != set_->tm.message().id()) no_tm.push_back(f);
  }
  const TimingReport r = analyse(no_tm);
  EXPECT_TRUE(has_problem(r, CaptureProblem::kNoTrigger)) << format_table(r);
  EXPECT_FALSE(has_problem(r, CaptureProblem::kTooShort));
}

TEST_F(Timing, ACaptureShorterThanTheLongestPeriodIsAProblem) {
  // Both sides of the boundary: 49.9 ms of capture is too short, 50 ms is not.
  const Nanos t0 = trace_->front().time;
  for (const auto& [length, too_short] : {std::pair{49'900us, true}, std::pair{50'000us, false}}) {
    std::vector<frames::TimedFrame> part;
    for (const auto& f : *trace_) {
      if (f.time - t0 < length) part.push_back(f);
    }
    part.push_back({part.back().frame, t0 + length});  // the capture ends exactly there
    const TimingReport r = analyse(part);
    EXPECT_EQ(has_problem(r, CaptureProblem::kTooShort), too_short) << length.count() << "\n" << format_table(r);
    EXPECT_FALSE(has_problem(r, CaptureProblem::kNoTrigger));
  }
}

}  // namespace
}  // namespace canhil::timing
