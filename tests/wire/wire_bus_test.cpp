// The bus model's time and order: frames' wire time, arbitration at every
// idle instant, controllers' queues, a lone sender, bus-off and recovery.
// Figures from reference-figures.md ("The CAN wire and its fault
// confinement"), checked against ISO 11898-1:2015 (clauses 10 and 12.1.4)
// and Bosch CAN 2.0 part B (sections 3, 8 and 9).
#include "canhil/wire/wire_bus.hpp"

#include <gtest/gtest.h>
#include <linux/can/error.h>

#include <algorithm>

namespace canhil::wire {
namespace {

using std::chrono::microseconds;

frames::WireFrame frame(std::uint32_t id, std::uint8_t len = 8, bool extended = false, bool remote = false) {
  frames::WireFrame f;
  f.id = id;
  f.len = len;
  f.extended = extended;
  f.remote = remote;
  for (std::size_t i = 0; i < f.data.size(); ++i) f.data[i] = static_cast<std::uint8_t>(0x55);
  return f;
}

std::vector<WireEvent> run(WireBus& bus, Nanos until) {
  std::vector<WireEvent> out;
  bus.advance(until, out);
  return out;
}

std::vector<WireEvent> only(const std::vector<WireEvent>& events, WireEvent::Kind kind) {
  std::vector<WireEvent> out;
  std::copy_if(events.begin(), events.end(), std::back_inserter(out),
               [&](const WireEvent& e) { return e.kind == kind; });
  return out;
}

Nanos bit(std::uint32_t n, std::uint32_t rate = 1'000'000) { return frames::bits_to_time(n, rate); }

TEST(WireBus, AFrameEndsAtItsEndOfFrameAndTheBusIsFreeThreeBitsLater) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  bus.add_controller("b");
  const frames::WireFrame f = frame(0x100);
  const std::uint32_t bits = frames::count_bits(f).total();
  bus.submit(a, f, Nanos{0});
  EXPECT_EQ(bus.next_event(), bit(bits - 3)) << "the last bit of end of frame, before the intermission";
  EXPECT_TRUE(run(bus, bit(bits - 3) - Nanos{1}).empty()) << "one nanosecond before: nothing";
  const auto events = run(bus, bit(bits - 3));
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, WireEvent::Kind::kFrame);
  EXPECT_EQ(events[0].start, Nanos{0});
  EXPECT_EQ(events[0].at, bit(bits - 3));
  // A second frame given now waits for the intermission.
  bus.submit(a, f, bit(bits - 3));
  const auto second = only(run(bus, bit(3 * bits)), WireEvent::Kind::kFrame);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_EQ(second[0].start, bit(bits));
}

TEST(WireBus, AtEveryIdleInstantTheLowestIdentifierGoesFirstEachThreeBitsAfterThePrevious) {
  WireBus bus({});
  std::vector<ControllerId> c;
  for (int i = 0; i < 5; ++i) c.push_back(bus.add_controller("c" + std::to_string(i)));
  bus.submit(c[0], frame(0x300), Nanos{0});  // on the wire at once
  // While it is on the wire, the others queue; by id: 0x050, 0x100, 0x100 extended (same base), remote 0x050.
  bus.submit(c[1], frame(0x100), microseconds(10));
  bus.submit(c[2], frame(0x100u << 18, 8, true), microseconds(10));
  bus.submit(c[3], frame(0x050, 0, false, true), microseconds(20));
  bus.submit(c[4], frame(0x050), microseconds(30));
  const auto frames_seen = only(run(bus, microseconds(2000)), WireEvent::Kind::kFrame);
  ASSERT_EQ(frames_seen.size(), 5u);
  const std::vector<ControllerId> order{c[0], c[4], c[3], c[1], c[2]};
  for (std::size_t i = 0; i < order.size(); ++i) {
    EXPECT_EQ(frames_seen[i].controller, order[i]) << "frame " << i;
    if (i > 0) {
      EXPECT_EQ(frames_seen[i].start, frames_seen[i - 1].at + bit(3)) << "3 bits of intermission, frame " << i;
    }
  }
  EXPECT_EQ(frames_seen[1].frame.remote, false) << "a data frame before a remote one of the same id";
  EXPECT_EQ(frames_seen[4].frame.extended, true) << "a base frame before an extended one with the same 11 bits";
}

// The next frame is chosen as soon as the bus knows it (a calm bus: no
// rules, nobody bus-off), so the bus's next event is that frame's end, not
// the idle instant where it starts; a frame given before that instant still
// takes part, as arbitration at the instant would have it, and one given
// after it waits.
TEST(WireBus, TheNextFrameIsKnownBeforeItStartsAndAFrameGivenByThenStillTakesPart) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a"), b = bus.add_controller("b"), c = bus.add_controller("c"),
                     d = bus.add_controller("d"), e = bus.add_controller("e");
  auto end_of = [](const frames::WireFrame& f, Nanos start) { return start + bit(frames::count_bits(f).total() - 3); };
  bus.submit(a, frame(0x300), Nanos{0});
  bus.submit(b, frame(0x200), microseconds(10));
  const Nanos a_end = end_of(frame(0x300), Nanos{0});
  const Nanos idle = a_end + bit(3);
  ASSERT_EQ(only(run(bus, a_end), WireEvent::Kind::kFrame).size(), 1u);
  EXPECT_EQ(bus.next_event(), end_of(frame(0x200), idle)) << "b's frame, from the idle instant, is already known";
  bus.submit(c, frame(0x100), a_end + bit(1));  // before the idle instant: takes part, and wins
  EXPECT_EQ(bus.next_event(), end_of(frame(0x100), idle));
  std::vector<WireEvent> out;
  bus.advance(idle, out);
  bus.submit(d, frame(0x050), idle);             // at the idle instant itself: takes part, and wins
  bus.submit(e, frame(0x001), idle + Nanos{1});  // after it: waits for the next
  const auto seen = only(run(bus, std::chrono::milliseconds(2)), WireEvent::Kind::kFrame);
  ASSERT_EQ(seen.size(), 4u);
  EXPECT_EQ(seen[0].controller, d);
  EXPECT_EQ(seen[0].start, idle);
  EXPECT_EQ(seen[1].controller, e);
  EXPECT_EQ(seen[2].controller, c);
  EXPECT_EQ(seen[3].controller, b);
}

TEST(WireBus, AControllerSendsItsOwnFramesInOrderAHigherPriorityOneWaitsBehindItsFirst) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  const ControllerId b = bus.add_controller("b");
  bus.submit(b, frame(0x010), Nanos{0});
  bus.submit(a, frame(0x400), microseconds(1));
  bus.submit(a, frame(0x001), microseconds(1));  // behind a's own 0x400
  bus.submit(b, frame(0x200), microseconds(1));
  const auto seen = only(run(bus, microseconds(2000)), WireEvent::Kind::kFrame);
  ASSERT_EQ(seen.size(), 4u);
  EXPECT_EQ(seen[1].frame.id, 0x200u) << "b's 0x200 beats a's head 0x400";
  EXPECT_EQ(seen[2].frame.id, 0x400u);
  EXPECT_EQ(seen[3].frame.id, 0x001u);
}

TEST(WireBus, AFrameGivenAtTheInstantArbitrationBeginsTakesPart) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  const ControllerId b = bus.add_controller("b");
  std::vector<WireEvent> out;
  bus.advance(microseconds(5), out);
  bus.submit(a, frame(0x300), microseconds(5));
  bus.submit(b, frame(0x100), microseconds(5));  // same instant, lower id
  const auto seen = only(run(bus, microseconds(1000)), WireEvent::Kind::kFrame);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].frame.id, 0x100u);
  EXPECT_EQ(seen[0].start, microseconds(5));
}

TEST(WireBus, AtARateOfNoWholeNanosecondsPerBitTheTimeIsStillTheExactQuotient) {
  for (const std::uint32_t rate : {83'333u, 800'000u, 1'000'000u}) {
    WireConfig config;
    config.bit_rate = rate;
    WireBus bus(config);
    const ControllerId a = bus.add_controller("a");
    bus.add_controller("b");
    const frames::WireFrame f = frame(0x123);
    bus.submit(a, f, Nanos{0});
    const auto seen = only(run(bus, std::chrono::milliseconds(5)), WireEvent::Kind::kFrame);
    ASSERT_EQ(seen.size(), 1u) << rate;
    EXPECT_EQ(seen[0].at, frames::bits_to_time(frames::count_bits(f).total() - 3, rate)) << rate;
  }
}

TEST(WireBus, AFullQueueRefusesTheFrameAndCountsIt) {
  WireBus bus({});
  ControllerOptions small;
  small.queue_frames = 3;
  const ControllerId a = bus.add_controller("a", small);
  bus.add_controller("b");
  for (int i = 0; i < 3; ++i) EXPECT_EQ(bus.submit(a, frame(0x100), Nanos{0}), WireBus::Submit::kQueued);
  EXPECT_EQ(bus.submit(a, frame(0x100), Nanos{0}), WireBus::Submit::kQueueFull);
  EXPECT_EQ(bus.status(a).refused, 1u);
  EXPECT_EQ(bus.status(a).queued, 3u);
}

TEST(WireBus, FdWithBitRateSwitchingTakesItsDataPhaseAtTheDataRate) {
  WireConfig config;
  config.data_bit_rate = 5'000'000;
  WireBus bus(config);
  const ControllerId a = bus.add_controller("a");
  bus.add_controller("b");
  frames::WireFrame f = frame(0x100, 64);
  f.fd = true;
  f.brs = true;
  const frames::FrameBits bits = frames::count_bits(f);
  bus.submit(a, f, Nanos{0});
  const auto seen = only(run(bus, microseconds(2000)), WireEvent::Kind::kFrame);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].at, bit(bits.nominal - 3) + frames::bits_to_time(bits.fast, 5'000'000));
}

TEST(WireBus, ALoneSenderGetsAcknowledgementErrorsItsCounterStopsAt128) {
  // Nobody acknowledges: each attempt ends in an ACK error (TEC + 8) until
  // error-passive; then rule 3's first exception holds it at 128.
  WireBus bus({});
  const ControllerId a = bus.add_controller("alone");
  bus.submit(a, frame(0x123), Nanos{0});
  const auto events = run(bus, microseconds(20'000));
  EXPECT_TRUE(only(events, WireEvent::Kind::kFrame).empty()) << "never delivered";
  const auto errors = only(events, WireEvent::Kind::kError);
  ASSERT_GT(errors.size(), 20u);
  for (const WireEvent& e : errors) {
    EXPECT_NE(e.error.id & CAN_ERR_ACK, 0u);
    EXPECT_EQ(e.error.data[3], CAN_ERR_PROT_LOC_ACK);
    EXPECT_NE(e.error.data[2] & CAN_ERR_PROT_TX, 0);
  }
  EXPECT_EQ(errors[15].error.data[6], 128);
  EXPECT_NE(errors[15].error.id & CAN_ERR_CRTL, 0u) << "the 16th error takes it error-passive";
  EXPECT_EQ(errors[15].error.data[1], CAN_ERR_CRTL_TX_PASSIVE);
  EXPECT_EQ(bus.status(a).tec, 128);
  EXPECT_EQ(bus.status(a).state, ControllerState::kErrorPassive);
  EXPECT_EQ(bus.status(a).bus_offs, 0u);
  // An error-active attempt: up to the ACK slot, a 6-bit flag (nobody
  // superposes one), 8 delimiter, 3 intermission; an error-passive one
  // waits 8 bits more (suspend transmission).
  const std::uint32_t bits = frames::count_bits(frame(0x123)).total();
  const Nanos attempt = bit(bits - 12 + 1 + 6 + 8 + 3);
  EXPECT_EQ(errors[1].at - errors[0].at, attempt);
  EXPECT_EQ(errors[20].at - errors[19].at, attempt + bit(8));
}

TEST(WireBus, BusOffAfterThirtyTwoErrorsAndRecovery1408BitsLaterOnAnIdleBus) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  const ControllerId b = bus.add_controller("b");
  FaultRule hit;  // every frame 0x100 is hit
  hit.kind = FaultRule::Kind::kFrameErrors;
  hit.id = 0x100;
  bus.add_fault(hit);
  bus.submit(a, frame(0x100), Nanos{0});
  bus.submit(a, frame(0x101), Nanos{0});
  const auto events = run(bus, microseconds(20'000));
  const auto errors = only(events, WireEvent::Kind::kError);
  const auto bus_off =
      std::find_if(errors.begin(), errors.end(), [](const WireEvent& e) { return (e.error.id & CAN_ERR_BUSOFF) != 0; });
  ASSERT_NE(bus_off, errors.end());
  EXPECT_EQ(bus_off->controller, a);
  const auto a_errors =
      std::count_if(errors.begin(), bus_off + 1, [&](const WireEvent& e) { return e.controller == a; });
  EXPECT_EQ(a_errors, 32) << "TEC + 8 per error: 256 after 32";
  EXPECT_EQ(bus.status(b).rec, 31) << "b's 32 receive errors (rule 1), less a's one frame received since (rule 8)";
  const auto restarted = std::find_if(errors.begin(), errors.end(),
                                      [](const WireEvent& e) { return (e.error.id & CAN_ERR_RESTARTED) != 0; });
  ASSERT_NE(restarted, errors.end());
  // The bus fell idle after the last error frame (6 + 6 flag bits, 8 delimiter, 3 intermission
  // with its last 11 recessive): 128 x 11 recessive bits, 1.408 ms at 1 Mbit/s.
  const Nanos idle_from = bus_off->at + bit(6 + 6 + 8 + 3) - bit(11);
  EXPECT_EQ(restarted->at, idle_from + microseconds(1408));
  EXPECT_EQ(restarted->error.data[6], 0);
  EXPECT_EQ(bus.status(a).bus_offs, 1u);
  EXPECT_EQ(bus.status(a).restarts, 1u);
  // Its frame on the wire was dropped at bus-off; the one behind it went after the recovery.
  const auto sent = only(events, WireEvent::Kind::kFrame);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].frame.id, 0x101u);
  EXPECT_GE(sent[0].start, restarted->at);
}

TEST(WireBus, ARestartDelayOrARestartOnRequestBeginsTheRecovery) {
  for (const bool on_request : {false, true}) {
    WireBus bus({});
    ControllerOptions options;
    options.restart_delay = on_request ? std::nullopt : std::optional<Nanos>(std::chrono::milliseconds(100));
    const ControllerId a = bus.add_controller("a", options);
    bus.add_controller("b");
    FaultRule off;
    off.kind = FaultRule::Kind::kBusOff;
    off.controller = a;
    off.from = std::chrono::milliseconds(1);
    bus.add_fault(off);
    auto events = run(bus, std::chrono::milliseconds(50));
    ASSERT_EQ(events.size(), 1u);
    EXPECT_NE(events[0].error.id & CAN_ERR_BUSOFF, 0u);
    EXPECT_EQ(events[0].at, std::chrono::milliseconds(1));
    EXPECT_EQ(bus.submit(a, frame(0x100), std::chrono::milliseconds(50)), WireBus::Submit::kBusOff);
    if (on_request) {
      events = run(bus, std::chrono::milliseconds(500));
      EXPECT_TRUE(events.empty()) << "restart-ms 0: bus-off until restarted";
      EXPECT_TRUE(bus.restart(a, std::chrono::milliseconds(500)));
    }
    events = run(bus, std::chrono::milliseconds(600));
    const Nanos begins = on_request ? std::chrono::milliseconds(500) : std::chrono::milliseconds(101);
    ASSERT_GE(events.size(), 2u);
    EXPECT_NE(events[0].error.id & CAN_ERR_RESTARTED, 0u);
    EXPECT_EQ(events[0].at, begins + microseconds(1408));
    EXPECT_EQ(events[1].kind, WireEvent::Kind::kFrame) << "its queued frame goes after the recovery";
    EXPECT_FALSE(bus.restart(a, std::chrono::milliseconds(600))) << "not bus-off: nothing to restart";
  }
}

TEST(WireBus, TrafficCountsTowardRecoveryOneOccurrencePerFrameTail) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a");
  ControllerOptions deep;
  deep.queue_frames = 512;
  const ControllerId b = bus.add_controller("b", deep);
  bus.add_controller("c");
  FaultRule off;
  off.kind = FaultRule::Kind::kBusOff;
  off.controller = a;
  bus.add_fault(off);
  // b sends back to back: every frame's last 11 bits are recessive, the gaps none.
  for (int i = 0; i < 300; ++i) bus.submit(b, frame(0x200), Nanos{0});
  const auto events = run(bus, std::chrono::milliseconds(100));
  const auto sent = only(events, WireEvent::Kind::kFrame);
  const auto restarted = std::find_if(events.begin(), events.end(), [](const WireEvent& e) {
    return e.kind == WireEvent::Kind::kError && (e.error.id & CAN_ERR_RESTARTED) != 0;
  });
  ASSERT_NE(restarted, events.end());
  const auto before =
      std::count_if(sent.begin(), sent.end(), [&](const WireEvent& e) { return e.start < restarted->at; });
  EXPECT_EQ(before, 128) << "128 frames' tails: 128 occurrences of 11 recessive bits";
  // While bus-off, a received none of them.
  EXPECT_NE(std::find(sent[0].missed.begin(), sent[0].missed.end(), a), sent[0].missed.end());
}

// Each controller's count of frames received: every frame whole that it was
// on the bus for, not its own and not missed. The bus keeps these lazily
// while it is calm (no rules, nobody bus-off, every receive counter 0) and
// one by one otherwise; the count is the same through both and the changes
// between them: a lone sender's ACK errors, a controller removed, one added.
TEST(WireBus, FramesReceivedAreCountedThroughCalmErrorsAndControllersComingAndGoing) {
  WireBus bus({});
  std::vector<ControllerId> present{bus.add_controller("a"), bus.add_controller("b")};
  std::vector<std::uint64_t> expected(2, 0);
  Nanos now{0};
  auto send = [&](ControllerId from, int frames) {
    std::vector<WireEvent> out;
    for (int i = 0; i < frames; ++i) {
      bus.submit(from, frame(0x100 + from), now);
      now += microseconds(200);
      bus.advance(now, out);
    }
    for (const WireEvent& e : out) {
      if (e.kind != WireEvent::Kind::kFrame) continue;
      for (const ControllerId c : present) {
        if (c != e.controller && std::find(e.missed.begin(), e.missed.end(), c) == e.missed.end()) ++expected[c];
      }
    }
    for (const ControllerId c : present) EXPECT_EQ(bus.status(c).received, expected[c]) << "controller " << c;
  };
  send(0, 20);
  send(1, 15);
  EXPECT_EQ(expected[0], 15u);
  EXPECT_EQ(expected[1], 20u);
  // b removed: a is alone, nobody acknowledges (ACK errors), b's count stays.
  bus.remove_controller(1);
  present = {0};
  send(0, 5);
  EXPECT_GT(bus.status(0).tec, 0) << "a's frames went unacknowledged";
  EXPECT_EQ(bus.status(1).received, 20u);
  // c comes: a's frames get through again, and c counts from now.
  present.push_back(bus.add_controller("c"));
  expected.push_back(0);
  send(0, 12);
  send(present[1], 3);
  EXPECT_EQ(bus.status(present[1]).received, expected[present[1]]);
  EXPECT_GT(expected[present[1]], 0u);
  // A fault rule: frames fail, counters move, counted one by one from then on.
  FaultRule errors;
  errors.kind = FaultRule::Kind::kFrameErrors;
  errors.rate = 0.5;
  errors.from = now;
  errors.until = now + std::chrono::milliseconds(5);
  ASSERT_TRUE(bus.add_fault(errors));
  send(0, 40);
  EXPECT_GT(bus.status(present[1]).errors, 0u);
  send(present[1], 10);
}

// A controller taken off the bus (its endpoint closed): a frame of its that
// has started still ends whole, as it is, bytes and all; one only chosen to
// go next never starts, and the next in arbitration goes in its place.
TEST(WireBus, AControllerRemovedMidFrameEndsItWholeAndOneChosenButNotStartedNeverSends) {
  WireBus bus({});
  const ControllerId a = bus.add_controller("a"), b = bus.add_controller("b"), c = bus.add_controller("c");
  bus.add_controller("d");  // acknowledges c's frame when a and b are gone
  frames::WireFrame fa = frame(0x300);
  fa.data[0] = 0xA5;
  bus.submit(a, fa, Nanos{0}, 7);
  bus.submit(b, frame(0x100), microseconds(1));  // waits for a's frame, chosen to go next
  bus.submit(c, frame(0x200), microseconds(1));
  std::vector<WireEvent> out;
  bus.advance(microseconds(20), out);
  bus.remove_controller(a);  // mid-frame
  bus.advance(microseconds(20), out);
  const Nanos a_end = bit(frames::count_bits(fa).total() - 3);
  bus.advance(a_end, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].controller, a);
  EXPECT_EQ(out[0].tag, 7u);
  EXPECT_EQ(out[0].frame.data[0], 0xA5) << "the frame as it was sent, though its queue is gone";
  bus.remove_controller(b);  // chosen, not yet started
  const auto rest = only(run(bus, std::chrono::milliseconds(2)), WireEvent::Kind::kFrame);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0].controller, c);
  EXPECT_EQ(rest[0].start, a_end + bit(3));
}

TEST(WireBus, TheSameCallsGiveTheSameEvents) {
  auto once = [] {
    WireConfig config;
    config.seed = 7;
    WireBus bus(config);
    const ControllerId a = bus.add_controller("a");
    const ControllerId b = bus.add_controller("b");
    FaultRule ber;
    ber.kind = FaultRule::Kind::kBitErrors;
    ber.rate = 1e-3;
    bus.add_fault(ber);
    std::vector<WireEvent> out;
    for (int i = 0; i < 2000; ++i) {
      bus.submit(i % 2 ? a : b, frame(static_cast<std::uint32_t>(0x100 + i % 7)), microseconds(100 * i));
      bus.advance(microseconds(100 * i + 50), out);
    }
    bus.advance(std::chrono::seconds(1), out);
    std::vector<std::tuple<int, ControllerId, std::int64_t, std::uint32_t>> summary;
    for (const WireEvent& e : out)
      summary.emplace_back(static_cast<int>(e.kind), e.controller, e.at.count(),
                           e.kind == WireEvent::Kind::kFrame ? e.frame.id : e.error.id);
    return summary;
  };
  const auto first = once();
  EXPECT_EQ(first, once());
  const auto errors = std::count_if(first.begin(), first.end(), [](const auto& t) { return std::get<0>(t) == 1; });
  EXPECT_GT(errors, 0) << "a bit error rate of 1e-3 hits some of 2000 frames";
}

}  // namespace
}  // namespace canhil::wire
