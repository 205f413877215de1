// Fault rules: the text a user writes, and each kind doing what it says to the
// frames of its target only, reproducibly for a seed.
#include "canhil/can_nodes/fault.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/wire.hpp"

#include "support/counter_watch.hpp"
#include "support/test_paths.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

const std::vector<std::string> kNodes = {"FTT master", "Pic_base", "Motor1", "Motor2", "Pic_odom"};

class FaultTest : public test::WatchedTest {
 protected:
  std::shared_ptr<const frames::MessageSet> set = frames::MessageSet::load(test::shipped_dbc());
  FaultInjector injector(std::vector<std::string> texts, std::uint64_t seed = 1) {
    std::vector<FaultRule> rules;
    for (const auto& t : texts) rules.push_back(parse_fault(t));
    return FaultInjector(std::move(rules), set, kNodes, seed);
  }
  static frames::CanFrame frame(std::uint32_t id) {
    frames::CanFrame f;
    f.id = id;
    f.len = 8;
    return f;
  }
};

TEST_F(FaultTest, ParsesEveryKind) {
  const FaultRule drop = parse_fault("drop:M4_1:0.25");
  EXPECT_EQ(drop.kind, FaultKind::kDrop);
  EXPECT_EQ(drop.target, "M4_1");
  EXPECT_DOUBLE_EQ(drop.probability, 0.25);
  EXPECT_EQ(parse_fault("drop:*").probability, 1.0);
  const FaultRule delay = parse_fault("delay:M3_1:3.5");
  EXPECT_EQ(delay.kind, FaultKind::kDelay);
  EXPECT_EQ(delay.delay, 3500us);
  EXPECT_EQ(parse_fault("corrupt:M1:2:0.5").byte, 2);
  EXPECT_EQ(parse_fault("duplicate:M9").copies, 1);
  EXPECT_EQ(parse_fault("duplicate:M9:3").copies, 3);
  const FaultRule silence = parse_fault("silence:Motor2:5");
  EXPECT_EQ(silence.kind, FaultKind::kSilence);
  EXPECT_EQ(silence.from, 5s);
  EXPECT_EQ(parse_fault("drop:M1:1@2.5").from, 2500ms);
  const FaultRule error = parse_fault("error:*:0.01");
  EXPECT_EQ(error.kind, FaultKind::kErrorFrame);
  EXPECT_DOUBLE_EQ(error.probability, 0.01);
  EXPECT_EQ(parse_fault("error:M3_1").probability, 1.0);
  const FaultRule battery = parse_fault("battery:power24:2.5@10");
  EXPECT_EQ(battery.kind, FaultKind::kBattery);
  EXPECT_EQ(battery.target, "power24");
  EXPECT_DOUBLE_EQ(battery.drain_per_s, 0.025);
  EXPECT_EQ(battery.from, 10s);
}

TEST_F(FaultTest, ParsesTheWiresKindsAndTheirDurations) {
  const FaultRule ber = parse_fault("ber:*:1e-5@2+0.5");
  EXPECT_EQ(ber.kind, FaultKind::kBitErrors);
  EXPECT_DOUBLE_EQ(ber.bit_error_rate, 1e-5);
  EXPECT_EQ(ber.from, 2s);
  EXPECT_EQ(ber.until, 2500ms);
  EXPECT_EQ(parse_fault("noack:M6_1").kind, FaultKind::kNoAck);
  EXPECT_EQ(parse_fault("stuck:Motor1@1+0.01").kind, FaultKind::kStuckDominant);
  EXPECT_EQ(parse_fault("cut:Pic_odom").until, kNever);
  const FaultRule off = parse_fault("busoff:laptop@3");
  EXPECT_EQ(off.kind, FaultKind::kBusOff);
  EXPECT_EQ(off.target, kLaptopTarget);
  EXPECT_EQ(parse_fault("babble:Motor2").babble_id, 0u);
  EXPECT_EQ(parse_fault("babble:Motor2:0x7F0").babble_id, 0x7F0u);
  EXPECT_EQ(parse_fault("babble:Motor2:16").babble_id, 16u);
  for (const auto kind : {FaultKind::kBitErrors, FaultKind::kNoAck, FaultKind::kStuckDominant, FaultKind::kBabbling,
                          FaultKind::kCut, FaultKind::kBusOff}) {
    EXPECT_TRUE(wire_only(kind));
  }
  EXPECT_FALSE(wire_only(FaultKind::kErrorFrame)) << "error works on an instant bus too";
  // The laptop is a target of the wire's rules only; the injector lets them by.
  FaultInjector wire_rules = injector({"busoff:laptop", "noack:laptop", "cut:Motor1"});
  EXPECT_FALSE(wire_rules.on_send("Motor1", frame(0x111), 1s).drop) << "the wire does them, not the injector";
}

TEST_F(FaultTest, BadRulesSayWhatIsWrongAndTheSyntax) {
  for (const char* text : {"drop", "explode:M1", "drop:M1:2", "delay:M1", "delay:M1:-1", "corrupt:M1:8", "corrupt:M1:x",
                           "duplicate:M1:0", "silence:Motor1", "drop:M1@soon", "error:M1:1.5", "error:M1:0.5:2",
                           "battery:power48:1", "battery:*", "battery:logic:0", "battery:logic:101",
                           // Times past a year: 1e53 s once overflowed the nanosecond count (found by fuzz.commands).
                           "drop:M4_1:0.9@1e53", "silence:Motor1:1e53", "drop:M1@31536001", "drop:M1@-1",
                           // The wire's kinds: a whole-bus rate, one node, a standard id, a duration above 0.
                           "ber:Motor1:1e-5", "ber:*", "ber:*:2", "stuck:*", "busoff:*", "cut:Motor1:3",
                           "babble:Motor1:0x800", "babble:Motor1:x", "cut:Motor1@1+0", "drop:M1@1+2"}) {
    try {
      parse_fault(text);
      ADD_FAILURE() << text << " was accepted";
    } catch (const SetupError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(text), std::string::npos) << what;
      EXPECT_NE(what.find("KIND:TARGET"), std::string::npos) << what;
    }
  }
  try {
    injector({"drop:Motor9"});
    ADD_FAILURE() << "an unknown target was accepted";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("FTT_master"), std::string::npos) << e.what();
  }
  for (const char* not_a_node : {"drop:Laptop", "busoff:M6_1"}) {
    try {
      injector({not_a_node});
      ADD_FAILURE() << not_a_node << " was accepted";
    } catch (const SetupError& e) {
      EXPECT_NE(std::string(e.what()).find(not_a_node), std::string::npos) << e.what();
    }
  }
}

TEST_F(FaultTest, TheLaptopIsHitByNameOrByItsMessagesNeverByTheStar) {
  // `*` stays every node's frame: a run's draws and outcomes with the rules
  // it had before the reference handler's frames were hooked are unchanged.
  FaultInjector inj = injector({"drop:*", "delay:M6_1:10", "duplicate:laptop:2"});
  const auto id = [&](const char* name) { return set->codec().find(name)->id(); };
  const FaultDecision m6 = inj.on_send(kLaptopTarget, frame(id("M6_1")), 0s);
  EXPECT_FALSE(m6.drop);
  EXPECT_EQ(m6.delay, 10ms);
  EXPECT_EQ(m6.duplicates, 2);
  const FaultDecision m7 = inj.on_send(kLaptopTarget, frame(id("M7")), 0s);
  EXPECT_EQ(m7.delay, 0ms);
  EXPECT_EQ(m7.duplicates, 2);
  EXPECT_TRUE(inj.on_send("Pic_base", frame(id("M1")), 0s).drop);
  const auto counts = inj.counts();
  EXPECT_EQ(counts[0].matched, 1U) << "the star: Pic_base's frame only";
  EXPECT_EQ(counts[1].matched, 1U);
  EXPECT_EQ(counts[2].matched, 2U);
}

TEST_F(FaultTest, EachKindChangesOnlyItsTarget) {
  FaultInjector inj = injector({"drop:M4_1", "delay:M3_1:2", "corrupt:M1:3", "duplicate:M9:2"});
  const auto id = [&](const char* name) { return set->codec().find(name)->id(); };
  EXPECT_TRUE(inj.on_send("Pic_odom", frame(id("M4_1")), 0s).drop);
  EXPECT_FALSE(inj.on_send("Pic_odom", frame(id("M4_2")), 0s).drop);
  EXPECT_EQ(inj.on_send("Motor1", frame(id("M3_1")), 0s).delay, 2ms);
  EXPECT_EQ(inj.on_send("Motor2", frame(id("M3_2")), 0s).delay, 0ms);
  EXPECT_EQ(inj.on_send("Pic_base", frame(id("M1")), 0s).corrupt_byte, 3);
  EXPECT_EQ(inj.on_send("Pic_base", frame(id("M2")), 0s).corrupt_byte, -1);
  EXPECT_EQ(inj.on_send("Pic_base", frame(id("M9")), 0s).duplicates, 2);
  for (const FaultCount& c : inj.counts()) {
    EXPECT_EQ(c.matched, 1u) << c.rule;
    EXPECT_EQ(c.applied, 1u) << c.rule;
  }
}

TEST_F(FaultTest, SilenceAndStartTimesActFromTheirTimeOn) {
  FaultInjector inj = injector({"silence:Motor1:2", "drop:M4_2:1@1"});
  const auto m3 = frame(set->codec().find("M3_1")->id());
  const auto m4 = frame(set->codec().find("M4_2")->id());
  EXPECT_FALSE(inj.on_send("Motor1", m3, 1999ms).drop);
  EXPECT_TRUE(inj.on_send("Motor1", m3, 2s).drop);
  EXPECT_TRUE(inj.on_send("Motor1", m3, 100s).drop);
  EXPECT_FALSE(inj.on_send("Motor2", m3, 100s).drop) << "another node";
  EXPECT_FALSE(inj.on_send("Pic_odom", m4, 999ms).drop);
  EXPECT_TRUE(inj.on_send("Pic_odom", m4, 1s).drop);
}

TEST_F(FaultTest, RuleTimesCountFromTheRunsStart) {
  // In real time the nodes' clock is the wall clock: 5 s means 5 s into the run.
  FaultInjector inj = injector({"silence:Motor1:5", "battery:*:10@2"});
  const Nanos start = 1'800'000'000s;
  inj.start_at(start);
  const auto m3 = frame(set->codec().find("M3_1")->id());
  EXPECT_FALSE(inj.on_send("Motor1", m3, start + 4s).drop);
  EXPECT_TRUE(inj.on_send("Motor1", m3, start + 5s).drop);
  EXPECT_EQ(inj.battery_drain_until(start + 2s), (std::array<double, 3>{0, 0, 0}));
  const auto drain = inj.battery_drain_until(start + 3s);
  for (double d : drain) EXPECT_NEAR(d, 0.10, 1e-9);
}

TEST_F(FaultTest, AnErrorFrameDelaysTheFrameByItsRetransmission) {
  FaultInjector inj = injector({"error:M3_1"});
  const auto m3_1 = frame(set->codec().find("M3_1")->id());
  const FaultDecision d = inj.on_send("Motor1", m3_1, 0s);
  EXPECT_TRUE(d.error_frame);
  // The destroyed frame and the error frame pass first: 1 us a bit at 1 Mbit/s.
  EXPECT_EQ(d.delay, std::chrono::microseconds(frames::frame_bits(m3_1) + frames::kErrorFrameBits));
  EXPECT_FALSE(inj.on_send("Motor2", frame(set->codec().find("M3_2")->id()), 0s).error_frame);
  std::vector<FaultRule> slow = {parse_fault("error:*")};
  FaultInjector at_125k(slow, set, kNodes, 1, 125'000);
  EXPECT_EQ(at_125k.on_send("Motor1", m3_1, 0s).delay, 8 * d.delay) << "eight times as long at 125 kbit/s";
}

// On a timed wire an `error` rule is the wire's (a bit error in the frames
// of its target): the injector passes its frames by, and its summary says
// where its counts are instead of "matched 0 frames".
TEST_F(FaultTest, AnErrorRuleLeftToTheWireSaysItsCountsAreTheControllers) {
  FaultInjector inj = injector({"error:Motor2:0.5", "drop:M3_1"});
  inj.leave_errors_to_the_wire(true);
  EXPECT_FALSE(inj.on_send("Motor2", frame(set->codec().find("M3_2")->id()), 0s).error_frame);
  EXPECT_EQ(describe(inj.counts()[0]), "on the wire: its counts are the controllers' (bus report)");
  EXPECT_EQ(describe(inj.counts()[1]).rfind("matched", 0), 0u) << "a drop rule stays the injector's";
  inj.leave_errors_to_the_wire(false);
  EXPECT_EQ(describe(inj.counts()[0]).rfind("matched", 0), 0u);
}

TEST_F(FaultTest, BatteryRulesDrainTheirPackFromTheirTimeOn) {
  FaultInjector inj = injector({"battery:power24:5", "battery:*:1@10"});
  auto drain = inj.battery_drain_until(2s);
  EXPECT_NEAR(drain[0], 0.0, 1e-12);
  EXPECT_NEAR(drain[2], 0.10, 1e-12) << "5 % a second for 2 s";
  drain = inj.battery_drain_until(12s);
  EXPECT_NEAR(drain[0], 0.02, 1e-12) << "the second rule from 10 s: 2 s at 1 %";
  EXPECT_NEAR(drain[2], 0.52, 1e-12);
  EXPECT_EQ(inj.counts()[0].active, 12s);
  EXPECT_EQ(inj.counts()[1].active, 2s);
  EXPECT_EQ(describe(inj.counts()[1]), "drained for 2.0 s");
  EXPECT_FALSE(inj.on_send("Pic_base", frame(set->codec().find("M1")->id()), 0s).drop) << "frames untouched";
}

TEST_F(FaultTest, ProbabilitiesHoldAndTheSeedReproducesThem) {
  const auto m4 = frame(set->codec().find("M4_1")->id());
  auto pattern = [&](std::uint64_t seed) {
    FaultInjector inj = injector({"drop:M4_1:0.3"}, seed);
    std::vector<bool> dropped;
    for (int k = 0; k < 10'000; ++k) dropped.push_back(inj.on_send("Pic_odom", m4, 0s).drop);
    EXPECT_EQ(inj.counts()[0].matched, 10'000u);
    EXPECT_EQ(inj.counts()[0].applied, static_cast<std::uint64_t>(std::count(dropped.begin(), dropped.end(), true)));
    return dropped;
  };
  const auto a = pattern(7);
  const auto n = std::count(a.begin(), a.end(), true);
  EXPECT_GT(n, 2'800);
  EXPECT_LT(n, 3'200);
  EXPECT_EQ(pattern(7), a);
  EXPECT_NE(pattern(8), a);
}

}  // namespace
}  // namespace canhil::can_nodes
