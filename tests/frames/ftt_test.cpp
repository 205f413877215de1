// The FTT schedule from the shipped DBC: which synchronous messages each EC
// carries, how long their window is, and the schedules it refuses.
#include "canhil/frames/ftt.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include "canhil/frames/dbc.hpp"
#include "canhil/frames/wire.hpp"
#include "support/test_paths.hpp"

namespace canhil::frames {
namespace {

using namespace std::chrono_literals;

class Ftt : public ::testing::Test {
 protected:
  std::uint32_t bit(const char* name) const { return 1u << set_->ftt(*set_->codec().find(name)).index; }
  std::shared_ptr<const frames::MessageSet> set_ = frames::MessageSet::load(test::shipped_dbc());
};

TEST_F(Ftt, EveryMessageIsDueEveryPeriodFromEcZeroAndNeverBetween) {
  const FttSchedule s(*set_, FttConfig{});
  const std::pair<const char*, int> periods[] = {{"M1", 3},   {"M3_1", 1}, {"M3_2", 1}, {"M3_3", 1}, {"M4_1", 5},
                                                 {"M4_2", 5}, {"M6_1", 3}, {"M6_2", 3}, {"M8", 5},   {"M9", 3}};
  for (const auto& [name, every] : periods) {
    for (std::uint64_t ec = 0; ec < 30; ++ec) {
      EXPECT_EQ((s.bitmap(ec) & bit(name)) != 0, ec % static_cast<std::uint64_t>(every) == 0) << name << " EC " << ec;
    }
  }
  EXPECT_EQ(s.bitmap(0), s.bitmap(15)) << "the schedule repeats every lcm(1, 3, 5) = 15 ECs";
  EXPECT_EQ(std::popcount(s.bitmap(0)), 10) << "EC 0 carries every synchronous message";
  EXPECT_EQ(s.bitmap(1), bit("M3_1") | bit("M3_2") | bit("M3_3"));
}

TEST_F(Ftt, TheWindowIsTheWorstCaseWireTimeOfWhatIsDuePlusTheGuard) {
  FttConfig config;
  const FttSchedule s(*set_, config);
  const Nanos frame = frames::bits_to_time(frames::worst_case_frame_bits(8), config.bit_rate);
  EXPECT_EQ(s.sync_window(0), Nanos{0}) << "nothing due, no window";
  EXPECT_EQ(s.sync_window(s.bitmap(1)), 3 * frame + config.sync_window_guard);
  EXPECT_EQ(s.sync_window(s.bitmap(0)), 10 * frame + config.sync_window_guard);
  FttConfig slower = config;
  slower.bit_rate = 500'000;
  EXPECT_EQ(FttSchedule(*set_, slower).sync_window(s.bitmap(1)), 2 * 3 * frame + config.sync_window_guard);
}

TEST(FttScheduleCycles, ACycleTooLongToTableIsWorkedOutEachEcByTheSameRule) {
  // M8 every 257 ECs and M9 every 256: the schedule repeats only after
  // lcm(1, 3, 5, 256, 257) = 986 880 ECs, more than the schedule tables.
  std::ifstream in(test::shipped_dbc());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"BO_ 321 50;", "BO_ 321 2570;"},
                                 std::pair<std::string, std::string>{"BO_ 337 30;", "BO_ 337 2560;"}}) {
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  }
  const auto set = frames::MessageSet::create(frames::parse_dbc(text, "long_cycle.dbc"));
  const auto shipped = frames::MessageSet::load(test::shipped_dbc());
  const FttSchedule slow(*set, FttConfig{});
  const FttSchedule tabled(*shipped, FttConfig{});
  const auto bit = [&](const char* name) { return 1u << set->ftt(*set->codec().find(name)).index; };
  const std::uint32_t m8 = bit("M8");
  const std::uint32_t m9 = bit("M9");
  for (const std::uint64_t ec : {0ULL, 1ULL, 255ULL, 256ULL, 257ULL, 512ULL, 771ULL, 65792ULL, 986880ULL, 986881ULL}) {
    EXPECT_EQ((slow.bitmap(ec) & m8) != 0, ec % 257 == 0) << "EC " << ec;
    EXPECT_EQ((slow.bitmap(ec) & m9) != 0, ec % 256 == 0) << "EC " << ec;
    EXPECT_EQ(slow.bitmap(ec) & ~(m8 | m9), tabled.bitmap(ec) & ~(m8 | m9))
        << "the other messages as shipped, EC " << ec;
  }
}

TEST(FttScheduleChecks, RefusesAScheduleThatDoesNotFit) {
  auto set = frames::MessageSet::load(test::shipped_dbc());
  FttConfig slow;
  slow.bit_rate = 125'000;
  try {
    FttSchedule s(*set, slow);
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("does not fit the 10000 us elementary cycle"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("raise the bit rate"), std::string::npos);
  }
  FttConfig odd;
  odd.elementary_cycle = 7ms;
  EXPECT_THROW(FttSchedule(*set, odd), SetupError);
}

TEST(FttScheduleChecks, AnAnalysisGetsTheMisfitReportedWithTheScheduleBuiltByTheSameRules) {
  auto set = frames::MessageSet::load(test::shipped_dbc());
  FttConfig slow;
  slow.bit_rate = 125'000;
  const FttSchedule s(FttSchedule::entries(*set, slow.bit_rate), slow, FttSchedule::Fit::kReport);
  EXPECT_FALSE(s.fits());
  EXPECT_NE(s.misfit().find("does not fit the 10000 us elementary cycle"), std::string::npos) << s.misfit();
  EXPECT_EQ(s.cycle_ecs(), 15u) << "periods of 1, 3 and 5 ECs";
  EXPECT_EQ(s.worst_ec(), 0u) << "every message is due in EC 0";
  const Nanos frame = bits_to_time(worst_case_frame_bits(8), slow.bit_rate);  // 1080 us
  EXPECT_EQ(s.longest_sync_window(), 10 * frame + slow.sync_window_guard);
  EXPECT_EQ(s.trigger_wire(), frame);
  EXPECT_EQ(s.longest_async_wire(), frame);
  const FttSchedule fast(FttSchedule::entries(*set, 1'000'000), FttConfig{}, FttSchedule::Fit::kReport);
  EXPECT_TRUE(fast.fits()) << fast.misfit();
  EXPECT_EQ(fast.bitmap(5), FttSchedule(*set, FttConfig{}).bitmap(5)) << "the master's own schedule";
}

TEST(FttScheduleChecks, TwoSynchronousMessagesOnOneIndexAreRefusedByName) {
  const std::vector<FttEntry> entries = {{"TM", FttKind::kTrigger, -1, 10ms, 135us},
                                         {"A", FttKind::kSync, 4, 20ms, 135us},
                                         {"B", FttKind::kSync, 4, 30ms, 135us}};
  try {
    FttSchedule s(entries, FttConfig{}, FttSchedule::Fit::kReport);
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("message B has FttIndex 4 like A"), std::string::npos) << e.what();
  }
}

TEST_F(Ftt, AnEcOtherThanTheTriggerPeriodIsRefusedSayingBoth) {
  FttConfig config;
  config.elementary_cycle = 20ms;
  try {
    FttSchedule s(*set_, config);
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("trigger message TM has period 10000 us"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canhil::frames
