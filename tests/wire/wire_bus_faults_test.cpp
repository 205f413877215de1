// Faults at the bus's level (wire_fault.hpp): what each does to the frames
// and the controllers' counters, and that the seed decides it.
#include <gtest/gtest.h>
#include <linux/can/error.h>

#include <algorithm>

#include "canhil/wire/wire_bus.hpp"

namespace canhil::wire {
namespace {

using std::chrono::microseconds;
using std::chrono::milliseconds;

frames::WireFrame eight_bytes(std::uint32_t id) {
  frames::WireFrame f;
  f.id = id;
  f.len = 8;
  return f;
}

std::vector<WireEvent> frames_of(const std::vector<WireEvent>& events) {
  std::vector<WireEvent> out;
  std::copy_if(events.begin(), events.end(), std::back_inserter(out),
               [](const WireEvent& e) { return e.kind == WireEvent::Kind::kFrame; });
  return out;
}

TEST(WireFaults, ABitErrorRateHitsFramesInProportionToTheirBits) {
  WireConfig config;
  config.seed = 3;
  WireBus bus(config);
  const ControllerId a = bus.add_controller("a");
  bus.add_controller("b");
  FaultRule ber;
  ber.kind = FaultRule::Kind::kBitErrors;
  ber.rate = 1e-4;
  bus.add_fault(ber);
  std::vector<WireEvent> out;
  const int n = 20'000;
  for (int i = 0; i < n; ++i) {
    bus.submit(a, eight_bytes(0x100), microseconds(200 * i));
    bus.advance(microseconds(200 * i + 199), out);
  }
  const auto failed = std::count_if(out.begin(), out.end(), [&](const WireEvent& e) {
    return e.kind == WireEvent::Kind::kError && e.controller == a;
  });
  // P(a frame of ~111..135 bits, ~120 before its intermission, is hit) ~ 1.2 %: about 240 of 20 000.
  EXPECT_GT(failed, 150);
  EXPECT_LT(failed, 350);
  EXPECT_EQ(frames_of(out).size(), static_cast<std::size_t>(n)) << "every frame gets through in the end, sent again";
}

TEST(WireFaults, FrameErrorsHitOnlyTheFramesOfTheirIdentifierInTheirWindow) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  const ControllerId b = bus.add_controller("b");
  bus.add_controller("c");
  FaultRule rule;  // one frame 0x200 in ten: b's counter stays low, nobody goes bus-off
  rule.kind = FaultRule::Kind::kFrameErrors;
  rule.rate = 0.1;
  rule.id = 0x200;
  rule.from = milliseconds(10);
  rule.until = milliseconds(20);
  bus.add_fault(rule);
  std::vector<WireEvent> out;
  for (int ms = 0; ms < 30; ++ms) {
    bus.submit(a, eight_bytes(0x100), milliseconds(ms));
    bus.submit(b, eight_bytes(0x200), milliseconds(ms));
    bus.advance(milliseconds(ms) + microseconds(999), out);
  }
  for (const WireEvent& e : out) {
    if (e.kind != WireEvent::Kind::kError) continue;
    EXPECT_GE(e.at, milliseconds(10));
    EXPECT_LT(e.at, milliseconds(21));
    if ((e.error.data[2] & CAN_ERR_PROT_TX) != 0) {
      EXPECT_EQ(e.controller, b) << "only 0x200's sender sees its own errors";
    }
  }
  EXPECT_GT(bus.status(b).errors, 0u);
  EXPECT_EQ(bus.status(a).tec, 0);
  EXPECT_EQ(bus.status(a).errors, bus.status(b).errors) << "a saw each of b's errors as a receiver";
}

TEST(WireFaults, AStuckDominantBusTakesTransmittersBusOffAndReceiversPassive) {
  WireBus bus({});
  ControllerOptions manual;
  manual.restart_delay = std::nullopt;
  const ControllerId a = bus.add_controller("a", manual);
  const ControllerId b = bus.add_controller("b");
  const ControllerId c = bus.add_controller("c");
  FaultRule stuck;
  stuck.kind = FaultRule::Kind::kStuckDominant;
  stuck.from = milliseconds(1);
  stuck.until = milliseconds(5);
  bus.add_fault(stuck);
  std::vector<WireEvent> out;
  bus.submit(a, eight_bytes(0x100), milliseconds(1) - microseconds(50));  // on the wire when the bus sticks
  bus.submit(a, eight_bytes(0x101), milliseconds(1));
  bus.advance(milliseconds(5) - Nanos{1}, out);
  EXPECT_TRUE(frames_of(out).empty()) << "nothing gets through";
  EXPECT_EQ(bus.status(a).state, ControllerState::kBusOff);
  EXPECT_EQ(bus.status(b).state, ControllerState::kErrorPassive);
  // a's bit error, then + 8 every 8 dominant bits: bus-off within 20 + 31 x 8 bits of the bus sticking.
  const auto off =
      std::find_if(out.begin(), out.end(), [&](const WireEvent& e) { return (e.error.id & CAN_ERR_BUSOFF) != 0; });
  ASSERT_NE(off, out.end());
  EXPECT_LE(off->at, milliseconds(1) + microseconds(20 + 31 * 8));
  // After the window: c's frame goes 11 recessive bits after the bus lets go.
  bus.submit(c, eight_bytes(0x300), milliseconds(5));
  out.clear();
  bus.advance(milliseconds(10), out);
  const auto sent = frames_of(out);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].start, milliseconds(5) + microseconds(11));
  EXPECT_EQ(bus.status(b).rec, kRecAfterPassiveReception) << "b's REC back under 128 by its first reception";
}

TEST(WireFaults, ACutCableLeavesTheControllerAloneBothWays) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  const ControllerId b = bus.add_controller("b");
  bus.add_controller("c");  // acknowledges b's frame while a is off the bus
  FaultRule cut;
  cut.kind = FaultRule::Kind::kCut;
  cut.controller = a;
  cut.from = milliseconds(1);
  cut.until = milliseconds(20);
  bus.add_fault(cut);
  std::vector<WireEvent> out;
  bus.submit(a, eight_bytes(0x100), milliseconds(2));
  bus.submit(b, eight_bytes(0x200), milliseconds(2));
  bus.advance(milliseconds(19), out);
  const auto sent = frames_of(out);
  ASSERT_EQ(sent.size(), 1u) << "b's frame only";
  EXPECT_EQ(sent[0].controller, b);
  EXPECT_EQ(sent[0].missed, std::vector<ControllerId>{a});
  EXPECT_EQ(bus.status(a).tec, 128) << "ACK errors on its own stub, up to error-passive";
  EXPECT_FALSE(bus.status(a).connected);
  EXPECT_EQ(bus.status(b).rec, 0) << "b saw none of it";
  out.clear();
  bus.advance(milliseconds(25), out);
  const auto after = frames_of(out);
  ASSERT_EQ(after.size(), 1u) << "reconnected, a's frame gets through";
  EXPECT_EQ(after[0].controller, a);
  EXPECT_GE(after[0].start, milliseconds(20));
}

TEST(WireFaults, ABabblingNodeStarvesLowerPriorities) {
  WireBus bus({});
  const ControllerId babbler = bus.add_controller("babbler");
  const ControllerId b = bus.add_controller("b");
  FaultRule babble;
  babble.kind = FaultRule::Kind::kBabbling;
  babble.controller = babbler;
  babble.babble = eight_bytes(0x000);
  babble.from = milliseconds(1);
  babble.until = milliseconds(3);
  bus.add_fault(babble);
  std::vector<WireEvent> out;
  bus.submit(b, eight_bytes(0x100), milliseconds(1) + microseconds(10));
  bus.advance(milliseconds(10), out);
  const auto sent = frames_of(out);
  ASSERT_GT(sent.size(), 10u);
  EXPECT_EQ(sent.back().controller, b) << "b's frame waits for the babbling to stop";
  EXPECT_GE(sent.back().start, milliseconds(3) - microseconds(200));
  EXPECT_EQ(sent.front().tag, kBabbleTag);
}

TEST(WireFaults, NoAcknowledgementForOneControllersFrames) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  bus.add_controller("b");
  FaultRule no_ack;
  no_ack.kind = FaultRule::Kind::kNoAck;
  no_ack.controller = a;
  no_ack.until = milliseconds(10);
  bus.add_fault(no_ack);
  std::vector<WireEvent> out;
  bus.submit(a, eight_bytes(0x100), Nanos{0});
  bus.advance(milliseconds(9), out);
  EXPECT_TRUE(frames_of(out).empty());
  EXPECT_EQ(bus.status(a).tec, 128);
  bus.clear_faults(milliseconds(9));
  out.clear();
  bus.advance(milliseconds(12), out);
  EXPECT_EQ(frames_of(out).size(), 1u) << "cleared: acknowledged again";
}

}  // namespace
}  // namespace canhil::wire
