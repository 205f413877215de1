#include "canhil/can_nodes/memory_bus.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include "canhil/frames/wire.hpp"

namespace canhil::can_nodes {
namespace {

using frames::make_data_frame;
using namespace std::chrono_literals;

TEST(MemoryBus, DeliversToEveryOtherEndpointStampedWithTheClock) {
  SimulatedClock clock(5ms);
  MemoryBus bus(clock);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  ASSERT_EQ(a->send(make_data_frame(0x131, {1, 2})), SendStatus::kOk);
  EXPECT_FALSE(a->receive()) << "no own frames by default, like SocketCAN";
  for (auto* e : {b.get(), c.get()}) {
    const auto f = e->receive();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame, make_data_frame(0x131, {1, 2}));
    EXPECT_EQ(f->time, 5ms);
    EXPECT_FALSE(e->receive());
  }
  EXPECT_EQ(bus.frames_carried(), 1u);
  EXPECT_EQ(a->stats().sent, 1u);
  EXPECT_EQ(b->stats().received, 1u);
}

TEST(MemoryBus, KeepsSendOrderAndTimestampsAsTheClockMoves) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto rx = bus.attach("rx");
  for (std::uint8_t i = 0; i < 10; ++i) {
    tx->send(make_data_frame(0x100 + i, {i}));
    clock.advance(1ms);
  }
  for (std::uint8_t i = 0; i < 10; ++i) {
    const auto f = rx->receive();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame.id, 0x100u + i);
    EXPECT_EQ(f->time, std::chrono::milliseconds(i));
  }
}

TEST(MemoryBus, ReceiveOwnWhenAsked) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto a = bus.attach("a");
  a->set_receive_own(true);
  a->send(make_data_frame(0x10, {}));
  EXPECT_TRUE(a->receive());
}

TEST(MemoryBus, FiltersLikeSocketCan) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto rx = bus.attach("rx");
  const Filter filters[] = {Filter::exact(0x131), Filter{0x110, 0x7F0, false, false, false, false, false}};
  rx->set_filters(filters);
  for (std::uint32_t id : {0x100u, 0x111u, 0x112u, 0x131u, 0x132u}) tx->send(make_data_frame(id, {}));
  std::vector<std::uint32_t> got;
  while (auto f = rx->receive()) got.push_back(f->frame.id);
  EXPECT_EQ(got, (std::vector<std::uint32_t>{0x111, 0x112, 0x131}));

  rx->set_filters({});
  tx->send(make_data_frame(0x131, {}));
  EXPECT_FALSE(rx->receive()) << "an empty filter list receives nothing";

  const Filter inverted[] = {Filter{0x131, 0x7FF, false, false, false, false, true}};
  rx->set_filters(inverted);
  tx->send(make_data_frame(0x131, {}));
  tx->send(make_data_frame(0x132, {}));
  const auto f = rx->receive();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->frame.id, 0x132u);
  EXPECT_FALSE(rx->receive());
}

TEST(MemoryBus, AnEndpointTakesExactlyWhatItsFiltersMatch) {
  // Standard data frames are decided by a table built from the filters;
  // every other frame by the filters themselves. Both must agree with them.
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto rx = bus.attach("rx");
  std::mt19937 pick(5);
  for (int round = 0; round < 40; ++round) {
    std::vector<Filter> filters(pick() % 4);
    for (Filter& f : filters) {
      f = Filter{static_cast<std::uint32_t>(pick() % 0x800),
                 static_cast<std::uint32_t>(pick() % 0x800),
                 pick() % 4 == 0,
                 pick() % 4 == 0,
                 pick() % 2 == 0,
                 pick() % 2 == 0,
                 pick() % 3 == 0};
    }
    rx->set_filters(filters);
    for (int k = 0; k < 200; ++k) {
      frames::CanFrame f = make_data_frame(static_cast<std::uint32_t>(pick() % 0x800), {});
      f.extended = pick() % 5 == 0;
      if (pick() % 5 == 0) f.kind = frames::FrameKind::kRemote;
      const bool want = std::any_of(filters.begin(), filters.end(), [&](const Filter& x) { return x.matches(f); });
      EXPECT_FALSE(rx->may_have_frames());
      tx->send(f);
      EXPECT_EQ(rx->may_have_frames(), want);
      const auto got = rx->receive();
      ASSERT_EQ(got.has_value(), want) << "round " << round << ", id " << f.id << (f.extended ? " extended" : "")
                                       << (f.kind == frames::FrameKind::kRemote ? " remote" : "");
    }
  }
}

TEST(MemoryBus, ErrorFramesOnlyWhereTheMaskAsks) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto quiet = bus.attach("quiet");
  auto watcher = bus.attach("watcher");
  watcher->set_error_mask(frames::kErrorClassBusOff | frames::kErrorClassController);
  bus.inject_error(frames::kErrorClassBusOff);
  bus.inject_error(frames::kErrorClassNoAck);
  EXPECT_FALSE(quiet->receive());
  const auto f = watcher->receive();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->frame.kind, frames::FrameKind::kError);
  EXPECT_EQ(f->frame.id, frames::kErrorClassBusOff);
  EXPECT_FALSE(watcher->receive());
  EXPECT_EQ(watcher->stats().errors, 1u);
}

TEST(MemoryBus, ATapSeesWhatACatchAllEndpointWouldInOrderAndStampedAlike) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto all = bus.attach("all");  // what the tap should see, the slow way
  all->set_error_mask(frames::kErrorClassMask);
  std::vector<frames::TimedFrame> tapped;
  bus.set_tap([&tapped](const frames::TimedFrame& f) { tapped.push_back(f); });
  a->send(make_data_frame(0x131, {1}));
  clock.advance(1ms);
  frames::CanFrame extended = make_data_frame(0x1FFFF, {2});  // outside the per-id routes
  extended.extended = true;
  b->send(extended);
  bus.inject_error(frames::kErrorClassNoAck);
  clock.advance(1ms);
  bus.set_up(false);
  a->send(make_data_frame(0x10, {}));  // refused: a down bus carries nothing
  bus.set_up(true);
  b->send(make_data_frame(0x7FF, {3}));
  std::vector<frames::TimedFrame> expected;
  while (auto f = all->receive()) expected.push_back(*f);
  ASSERT_EQ(expected.size(), 4u);
  ASSERT_EQ(tapped.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(tapped[i].frame, expected[i].frame) << "frame " << i;
    EXPECT_EQ(tapped[i].time, expected[i].time) << "frame " << i;
  }
  bus.set_tap({});
  a->send(make_data_frame(0x131, {4}));
  EXPECT_EQ(tapped.size(), 4u) << "an empty function removes the tap";
}

TEST(MemoryBus, OverflowIsDroppedAndCounted) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto rx = bus.attach("rx", 3);
  for (int i = 0; i < 5; ++i) tx->send(make_data_frame(0x10, {}));
  EXPECT_EQ(rx->pending(), 3u);
  EXPECT_EQ(rx->stats().rx_overflow, 2u);
  EXPECT_EQ(rx->stats().received + rx->stats().rx_overflow, 5u) << "every frame received or counted";
}

TEST(MemoryBus, SendsAndReceivesInAnyInterleavingKeepOrderAndCapacity) {
  // The first waiting frame is held apart from the rest: any mix of sends and
  // receives must still give the frames in order, count the waiting ones and
  // drop past the capacity, as one queue would.
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto rx = bus.attach("rx", 5);
  std::deque<std::uint32_t> reference;
  std::uint64_t dropped = 0;
  std::mt19937 pick(17);
  std::uint32_t next = 0;
  for (int step = 0; step < 20'000; ++step) {
    if (pick() % 100 < 52) {
      tx->send(make_data_frame(next % 0x700, {}));
      if (reference.size() < 5) {
        reference.push_back(next % 0x700);
      } else {
        ++dropped;
      }
      ++next;
    } else {
      const auto f = rx->receive();
      ASSERT_EQ(f.has_value(), !reference.empty()) << "step " << step;
      if (f) {
        ASSERT_EQ(f->frame.id, reference.front()) << "step " << step;
        reference.pop_front();
      }
    }
    ASSERT_EQ(rx->pending(), reference.size()) << "step " << step;
    ASSERT_EQ(rx->may_have_frames(), !reference.empty()) << "step " << step;
  }
  EXPECT_EQ(rx->stats().rx_overflow, dropped);
  EXPECT_GT(dropped, 0u) << "the walk reached the capacity";
}

TEST(MemoryBus, DownBusRefusesSendsAndReportsState) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  bus.set_up(false);
  EXPECT_EQ(a->state(), BusState::kDown);
  EXPECT_EQ(a->send(make_data_frame(0x10, {})), SendStatus::kDown);
  EXPECT_FALSE(b->receive());
  bus.set_up(true);
  EXPECT_EQ(a->state(), BusState::kUp);
  EXPECT_EQ(a->stats().state_changes, 2u);
  EXPECT_EQ(a->send(make_data_frame(0x10, {})), SendStatus::kOk);
  EXPECT_TRUE(b->receive());
}

TEST(MemoryBus, DetachedEndpointGetsNothingAndBusOutlivingIsSafe) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto a = bus.attach("a");
  { auto b = bus.attach("b"); }
  EXPECT_EQ(a->send(make_data_frame(0x10, {})), SendStatus::kOk);
  EXPECT_EQ(bus.frames_carried(), 1u);
}

TEST(MemoryBus, WhoReceivesFollowsAttachDetachAndNewFiltersBetweenFrames) {
  // A frame visits only the endpoints whose filters take its id, a table the
  // bus keeps: it must follow every change made while traffic flows.
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto tx = bus.attach("tx");
  auto a = bus.attach("a");
  tx->send(make_data_frame(0x100, {}));
  auto late = bus.attach("late");
  tx->send(make_data_frame(0x100, {}));
  EXPECT_EQ(a->pending(), 2u);
  EXPECT_EQ(late->pending(), 1u) << "attached after the first frame";
  const Filter only_0x200[] = {Filter::exact(0x200)};
  a->set_filters(only_0x200);
  tx->send(make_data_frame(0x100, {}));
  tx->send(make_data_frame(0x200, {}));
  EXPECT_EQ(a->pending(), 3u) << "0x100 refused, 0x200 taken";
  EXPECT_EQ(late->pending(), 3u);
  late.reset();
  tx->set_receive_own(true);
  tx->send(make_data_frame(0x200, {}));
  EXPECT_EQ(a->pending(), 4u);
  EXPECT_EQ(tx->pending(), 1u) << "its own frame, once asked for";
  EXPECT_EQ(bus.frames_carried(), 5u);
}

TEST(Filter, MatchesExtendedAndRemoteFlagsWhenAsked) {
  frames::CanFrame ext = make_data_frame(0x131, {});
  ext.extended = true;
  EXPECT_FALSE(Filter::exact(0x131).matches(ext)) << "exact() compares the extended flag";
  EXPECT_TRUE(Filter::all().matches(ext));
  frames::CanFrame rtr = make_data_frame(0x131, {});
  rtr.kind = frames::FrameKind::kRemote;
  EXPECT_FALSE(Filter::exact(0x131).matches(rtr));
  EXPECT_TRUE(Filter::exact(0x131).matches(make_data_frame(0x131, {})));
}

TEST(MemoryBusWire, ArbitrationByIdentifierFramesOneAfterTheOtherNoPreemption) {
  SimulatedClock clock(1ms);
  MemoryBus bus(clock);
  bus.set_wire({1'000'000, Wire::Bits::kWorstCase});  // 8 data bytes: 135 us
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");
  auto rx = bus.attach("rx");
  Participant& wire = bus.wire_participant();
  a->send(make_data_frame(0x300, {1, 2, 3, 4, 5, 6, 7, 8}));  // first, but at the same instant as 0x100
  b->send(make_data_frame(0x100, {1, 2, 3, 4, 5, 6, 7, 8}));  // arbitration still open: wins
  EXPECT_EQ(bus.queued(), 2u) << "one on the wire, one waiting";
  EXPECT_FALSE(rx->receive()) << "nothing before its last bit";
  EXPECT_EQ(wire.next_wakeup(), 1ms + 132us) << "its end of frame: 135 bits less the 3 of intermission";
  clock.set(1ms + 50us);
  c->send(make_data_frame(0x050, {1, 2, 3, 4, 5, 6, 7, 8}));  // higher still, but 0x100 is on the wire
  std::vector<std::pair<std::uint32_t, Nanos>> got;
  while (wire.next_wakeup() != kNever) {
    clock.set(wire.next_wakeup());
    wire.tick(clock.now());
    while (auto f = rx->receive()) got.emplace_back(f->frame.id, f->time);
  }
  const std::vector<std::pair<std::uint32_t, Nanos>> expected = {
      {0x100, 1ms + 132us}, {0x050, 1ms + 267us}, {0x300, 1ms + 402us}};
  EXPECT_EQ(got, expected) << "each stamped at its end of frame, the lower identifier first at each idle bus";
}

TEST(MemoryBusWire, ExactBitsFollowThePayloadsStuffing) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  bus.set_wire({500'000, Wire::Bits::kExact});
  auto a = bus.attach("a");
  auto rx = bus.attach("rx");
  const frames::CanFrame f = make_data_frame(0x000, {0, 0, 0, 0, 0, 0, 0, 0});  // long runs: many stuff bits
  a->send(f);
  EXPECT_EQ(bus.wire_participant().next_wakeup(), frames::bits_to_time(frames::frame_bits(f) - 3, 500'000));
  EXPECT_GT(frames::frame_bits(f), frames::best_case_frame_bits(8));
}

TEST(MemoryBusWire, ABusOffEndpointReadsDownGetsNothingAndSeesItsErrorFrames) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  Wire wire{1'000'000};
  wire.controller.restart_delay = std::nullopt;  // stays bus-off until restarted
  bus.set_wire(wire);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  auto c = bus.attach("c");  // acknowledges b's frame while a is bus-off
  a->set_error_mask(frames::kErrorClassMask);
  wire::FaultRule off;
  off.kind = wire::FaultRule::Kind::kBusOff;
  off.controller = bus.controller_of(*a);
  off.from = 1ms;
  bus.wire_bus()->add_fault(off);
  clock.set(2ms);
  bus.wire_participant().tick(clock.now());
  EXPECT_EQ(a->state(), BusState::kDown) << "bus-off: the carrier is off, as can-dev's";
  EXPECT_EQ(b->state(), BusState::kUp);
  const auto err = a->receive();
  ASSERT_TRUE(err);
  EXPECT_EQ(err->frame.kind, frames::FrameKind::kError);
  EXPECT_NE(err->frame.id & frames::kErrorClassBusOff, 0u);
  EXPECT_EQ(err->time, 1ms);
  EXPECT_FALSE(b->receive()) << "b's mask takes no error frames, and a's errors are a's";
  b->send(make_data_frame(0x100, {1}));
  clock.set(3ms);
  bus.wire_participant().tick(clock.now());
  EXPECT_FALSE(a->receive()) << "a bus-off controller receives nothing";
  EXPECT_TRUE(c->receive());
  EXPECT_TRUE(bus.wire_bus()->restart(bus.controller_of(*a), clock.now()));
  clock.set(5ms);
  bus.wire_participant().tick(clock.now());
  EXPECT_EQ(a->state(), BusState::kUp) << "recovered 1.408 ms after the restart";
  const auto restarted = a->receive();
  ASSERT_TRUE(restarted);
  EXPECT_NE(restarted->frame.id & frames::kErrorClassRestarted, 0u);
  EXPECT_EQ(restarted->time, 3ms + 1408us);
}

TEST(MemoryBusWire, AFullTransmitQueueDropsTheFrameAsEnobufs) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  Wire wire{125'000};
  wire.controller.queue_frames = 4;
  bus.set_wire(wire);
  auto a = bus.attach("a");
  auto b = bus.attach("b");
  int dropped = 0;
  for (int i = 0; i < 10; ++i) {
    if (a->send(make_data_frame(0x100, {1, 2, 3})) == SendStatus::kDropped) ++dropped;
  }
  EXPECT_EQ(dropped, 6);
  EXPECT_EQ(a->stats().send_dropped, 6u);
  EXPECT_EQ(a->stats().sent, 4u);
}

}  // namespace
}  // namespace canhil::can_nodes
