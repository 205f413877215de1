// The analysis of a whole message set (canhil timing --analyse) on sets small
// enough to work out by hand, each figure's arithmetic in the comments. At
// 1 Mbit/s a bit is 1 us and an 8-byte standard frame takes at most 135 bits
// (interframe space included): C = 135 us. The EC is 10 ms and canhil's
// master adds a 20 us guard to every synchronous window.
#include "canhil/timing/bus_analysis.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/dbc.hpp"
#include "support/test_paths.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;
using frames::FttKind;

constexpr Nanos kC = 135us;

BusMessage trigger() { return {"TM", 0x010, false, 8, FttKind::kTrigger, -1, 10ms, {}, {}}; }
BusMessage sync(const char* name, std::uint32_t id, int index, Nanos period) {
  return {name, id, false, 8, FttKind::kSync, index, period, {}, {}};
}
BusMessage async(const char* name, std::uint32_t id, Nanos gap) {
  return {name, id, false, 8, FttKind::kAsync, -1, {}, gap, {}};
}

AnalysisConfig plain() {
  AnalysisConfig c;
  c.what_if = false;
  return c;
}

const AsyncBound& async_named(const BusAnalysis& a, const std::string& name) {
  for (const AsyncBound& m : a.async.messages) {
    if (m.name == name) return m;
  }
  throw std::runtime_error("no sporadic message " + name);
}

TEST(FttAnalysis, OneSynchronousAndOneSporadicMessage) {
  const BusSet set{{trigger(), sync("A", 0x100, 0, 10ms), async("S", 0x080, 100ms)}, true};
  const BusAnalysis a = analyse_bus(set, plain());
  ASSERT_TRUE(a.schedulable());
  // Synchronous: A in every EC; its window C + guard = 155 us; the LSW the
  // master leaves: EC - TM - the longest sporadic frame = 10000 - 135 - 135.
  EXPECT_EQ(a.sync.cycle_ecs, 1u);
  EXPECT_EQ(a.sync.longest_window, kC + 20us);
  EXPECT_EQ(a.sync.allowed_window, 9730us);
  EXPECT_TRUE(a.sync.fits);
  ASSERT_EQ(a.sync.messages.size(), 1u);
  EXPECT_EQ(a.sync.messages[0].worst_offset, kC);
  // U = 135 / 10000; bound 1 (2^1 - 1) (9730 - 20 - 135) / 10000 = 0.9575.
  EXPECT_DOUBLE_EQ(a.sync.utilisation, 0.0135);
  EXPECT_NEAR(a.sync.utilisation_bound, 0.9575, 1e-12);
  EXPECT_TRUE(a.sync.utilisation_test);
  // Sporadic: window 10000 - 135 - 155 = 9710 us, less the 135 us idle time
  // inserted at its end: 9575 us served each EC. S alone: no blocking, its own
  // frame from the window's opening (135 us); from ready it first waits up to
  // an EC and the TM (10135 us).
  EXPECT_EQ(a.async.shortest_window, 9710us);
  EXPECT_EQ(a.async.usable, 9575us);
  const AsyncBound& s = async_named(a, "S");
  EXPECT_EQ(s.blocking, 0ns);
  EXPECT_EQ(s.from_window, kC);
  EXPECT_EQ(s.worst_response, 10135us + kC);
  EXPECT_EQ(s.deadline, 100ms) << "its minimum gap";
  EXPECT_EQ(s.windows, 1);
}

TEST(FttAnalysis, TwoMessagesOfEqualPeriodGoOneAfterTheOtherInOneWindow) {
  const BusSet set{{trigger(), sync("A", 0x100, 0, 20ms), sync("B", 0x101, 1, 20ms), async("X", 0x080, 50ms),
                    async("Y", 0x090, 50ms)},
                   true};
  const BusAnalysis a = analyse_bus(set, plain());
  ASSERT_TRUE(a.schedulable());
  // Both due in EC 0 of a 2-EC cycle, none in EC 1: 2 C + guard = 290 us.
  EXPECT_EQ(a.sync.cycle_ecs, 2u);
  ASSERT_EQ(a.sync.ecs.size(), 2u);
  EXPECT_EQ(a.sync.ecs[0].window, 290us);
  EXPECT_EQ(a.sync.ecs[1].window, 0ns);
  ASSERT_EQ(a.sync.messages.size(), 2u);
  EXPECT_EQ(a.sync.messages[0].worst_offset, kC) << "A wins arbitration";
  EXPECT_EQ(a.sync.messages[1].worst_offset, 2 * kC) << "B ends after A";
  // Their window starts at the same place every cycle: intervals 20 ms give
  // or take the frame's end (A: 0..135 us into the window).
  EXPECT_EQ(a.sync.messages[0].interval_low, 20ms - kC);
  EXPECT_EQ(a.sync.messages[0].interval_high, 20ms + kC);
  // X is blocked by Y's frame (135) then sends its own; Y waits for one X
  // (ceil((r + EC + bit) / 50 ms) = 1 instance) then its own: both 270 us.
  EXPECT_EQ(async_named(a, "X").blocking, kC);
  EXPECT_EQ(async_named(a, "X").from_window, 2 * kC);
  EXPECT_EQ(async_named(a, "Y").blocking, 0ns);
  EXPECT_EQ(async_named(a, "Y").from_window, 2 * kC);
}

TEST(FttAnalysis, AWindowFullToTheLastBitFitsAndOneBitOverMisses) {
  const BusSet set{{trigger(), sync("A", 0x100, 0, 20ms), sync("B", 0x101, 1, 20ms), async("X", 0x080, 50ms)}, true};
  AnalysisConfig c = plain();
  c.sync_window = 290us;  // exactly A, B and the guard
  BusAnalysis a = analyse_bus(set, c);
  EXPECT_TRUE(a.sync.fits);
  EXPECT_TRUE(a.schedulable());
  c.sync_window = 289us;  // one bit (1 us) short
  a = analyse_bus(set, c);
  EXPECT_FALSE(a.sync.fits);
  EXPECT_FALSE(a.sync.messages[0].fits);
  ASSERT_FALSE(a.schedulable());
  EXPECT_EQ(a.misses.front().name, "A");
  EXPECT_EQ(a.misses.front().by, 1us) << "misses by one bit";
  c.what_if = true;
  c.copies_of = {"B"};
  a = analyse_bus(set, c);
  ASSERT_EQ(a.what_if.copies.size(), 1u);
  EXPECT_EQ(a.what_if.copies[0].copies, 0);
  EXPECT_EQ(a.what_if.copies[0].limited, "the set, which misses already") << "no room to count in";
}

TEST(FttAnalysis, SporadicDemandThatFillsAWindowExactlyTakesOneAndOneBitMoreTakesTheNextEc) {
  const BusSet set{{trigger(), sync("A", 0x100, 0, 10ms), async("X", 0x080, 500ms), async("Y", 0x090, 500ms)}, true};
  AnalysisConfig c = plain();
  // LSW chosen so that the shortest asynchronous window is 405 us: 10000 - 135
  // - 9460. Less the idle time (135): 270 us served, X and Y exactly.
  c.sync_window = 9460us;
  BusAnalysis a = analyse_bus(set, c);
  EXPECT_EQ(a.async.usable, 270us);
  EXPECT_EQ(async_named(a, "Y").from_window, 270us);
  EXPECT_EQ(async_named(a, "Y").windows, 1);
  c.sync_window = 9461us;  // 269 us served: Y's last bit in the next EC's window
  a = analyse_bus(set, c);
  EXPECT_EQ(async_named(a, "Y").windows, 2);
  EXPECT_EQ(async_named(a, "Y").from_window, 10ms + 1us) << "one full EC, then the bit left over";
}

TEST(FttAnalysis, WhatIfFindsTheLowestBitRateAndTheShortestEc) {
  const BusSet set{{trigger(), sync("A", 0x100, 0, 10ms), async("S", 0x080, 100ms)}, true};
  AnalysisConfig c;
  c.copies_of = {"A"};
  const BusAnalysis a = analyse_bus(set, c);
  // With f = 135 bits / r: the EC holds the TM, the window (A + 20 us), the
  // idle time and S's frame: 4 f + 20 us <= 10000 us, r >= 540 / 9980e-6 =
  // 54108.2 bit/s. (Wire times are whole ns, rounded down: at 54109 4 f =
  // 9979856 ns fits; at 54108 it is 9980040 ns, 40 ns over.)
  EXPECT_EQ(a.what_if.lowest_bit_rate, 54109u);
  // At 1 Mbit/s the same sum is 560 us: the shortest divisor of 10 ms at or
  // above it is 625 us.
  EXPECT_EQ(a.what_if.shortest_ec, 625us);
  ASSERT_EQ(a.what_if.copies.size(), 1u);
  EXPECT_EQ(a.what_if.copies[0].copies, 31) << "every other FTT index";
  EXPECT_EQ(a.what_if.copies[0].limited, "the free FTT indices (32 in all)");
}

TEST(FttAnalysis, TheShippedSetIsSchedulableWithTheMarginsItsDocsGive) {
  const BusSet set = read_bus_set(frames::load_dbc(test::shipped_dbc()));
  ASSERT_TRUE(set.ftt);
  const BusAnalysis a = analyse_bus(set, AnalysisConfig{});
  ASSERT_TRUE(a.schedulable());
  // docs/timing.md: EC 0 carries all ten synchronous messages, 10 C + guard.
  EXPECT_EQ(a.sync.cycle_ecs, 15u);
  EXPECT_EQ(a.sync.worst_ec, 0u);
  EXPECT_EQ(a.sync.longest_window, 10 * kC + 20us);
  EXPECT_EQ(a.what_if.shortest_ec, 2ms);
  const auto m1 = std::find_if(a.what_if.copies.begin(), a.what_if.copies.end(),
                               [](const CopiesLimit& l) { return l.name == "M1"; });
  ASSERT_NE(m1, a.what_if.copies.end());
  EXPECT_EQ(m1->copies, 22) << "32 indices less the ten in use";
}

TEST(NativeBus, ADbcWithoutATriggerMessageIsAnalysedAsNativeCan) {
  const char* dbc = R"(VERSION ""
BU_: A B
BO_ 256 Fast: 8 A
 SG_ x : 0|8@1+ (1,0) [0|255] "" B
BO_ 512 Slow: 8 B
 SG_ y : 0|8@1+ (1,0) [0|255] "" A
BA_DEF_ BO_  "GenMsgCycleTime" INT 0 65535;
BA_DEF_ BO_  "GenMsgDelayTime" INT 0 65535;
BA_ "GenMsgCycleTime" BO_ 256 1;
BA_ "GenMsgDelayTime" BO_ 512 5;
)";
  const BusSet set = read_bus_set(frames::parse_dbc(dbc, "native.dbc"));
  ASSERT_FALSE(set.ftt);
  const BusAnalysis a = analyse_bus(set, plain());
  ASSERT_EQ(a.native.messages.size(), 2u);
  // Fast: blocked by Slow's frame, then its own: 270 us; Slow: one Fast
  // queued in its wait, then its own: 270 us.
  EXPECT_EQ(a.native.messages[0].name, "Fast");
  EXPECT_EQ(a.native.messages[0].worst_response, 2 * kC);
  EXPECT_EQ(a.native.messages[1].worst_response, 2 * kC);
  EXPECT_EQ(a.native.messages[1].deadline, 5ms) << "a sporadic message's minimum gap";
  EXPECT_TRUE(a.schedulable());
}

TEST(NativeBus, AMessageWithNeitherPeriodNorGapIsNamedWithTheAttributeToSet) {
  const char* dbc = R"(VERSION ""
BU_: A
BO_ 256 Lost: 8 A
 SG_ x : 0|8@1+ (1,0) [0|255] "" A
)";
  try {
    read_bus_set(frames::parse_dbc(dbc, "lost.dbc"));
    FAIL();
  } catch (const SetupError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("lost.dbc:3"), std::string::npos) << text;
    EXPECT_NE(text.find("message Lost has neither a period nor a minimum gap"), std::string::npos) << text;
    EXPECT_NE(text.find("GenMsgCycleTime"), std::string::npos) << text;
  }
}

TEST(AddMessage, ASynchronousMessageTakesTheLowestFreeIndex) {
  BusSet set{{trigger(), sync("A", 0x100, 0, 10ms), sync("B", 0x101, 2, 10ms)}, true};
  add_message(set, "Sonar 0x180 4 20 sync");
  const BusMessage& m = set.messages.back();
  EXPECT_EQ(m.name, "Sonar");
  EXPECT_EQ(m.id, 0x180u);
  EXPECT_EQ(m.dlc, 4);
  EXPECT_EQ(m.period, 20ms);
  EXPECT_EQ(m.index, 1);
  add_message(set, "Alarm 0x18FF0001 8 250 async");
  EXPECT_TRUE(set.messages.back().extended);
  EXPECT_EQ(set.messages.back().min_gap, 250ms);
}

TEST(AddMessage, AMalformedOneNamesTheField) {
  const std::pair<const char*, const char*> cases[] = {
      {"Sonar 0x180 4 20", "got 4 fields"},
      {"Sonar 0x2000000000 4 20 sync", "ID: \"0x2000000000\" is not a CAN identifier"},
      {"Sonar 12z 4 20 sync", "ID: \"12z\""},
      {"Sonar 0x180 9 20 sync", "DLC: \"9\" is not a classic CAN length"},
      {"Sonar 0x180 4 -5 sync", "PERIOD_MS: \"-5\""},
      {"Sonar 0x180 4 fast sync", "PERIOD_MS: \"fast\""},
      {"Sonar 0x180 4 20 often", "KIND: \"often\""},
      {"A 0x180 4 20 sync", "NAME: the message set already has a message A"},
      {"Sonar 0x100 4 20 sync", "ID: 0x100 is A's"},
  };
  for (const auto& [text, expected] : cases) {
    BusSet set{{trigger(), sync("A", 0x100, 0, 10ms)}, true};
    try {
      add_message(set, text);
      ADD_FAILURE() << text << " was taken";
    } catch (const SetupError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << text << ": " << e.what();
      EXPECT_EQ(set.messages.size(), 2u) << "nothing added";
    }
  }
}

TEST(AddMessage, NoFreeIndexIsSaid) {
  BusSet set{{trigger()}, true};
  for (int i = 0; i < 32; ++i) set.messages.push_back(sync("S", 0x100 + static_cast<std::uint32_t>(i), i, 10ms));
  try {
    add_message(set, "More 0x300 8 10 sync");
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("all 32 FTT indices"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canhil::timing
