// The broker's timed interfaces (userbus/src/broker_wire.hpp) without
// processes: the broker's clock given by the test, so every figure is exact.
// The wire's own rules are checked in tests/wire/; here, what the broker adds:
// a controller per process, frames back as the program wrote them at their
// end of frame, the shared transmit-queue counts the preload's ENOBUFS reads,
// error frames as Linux's, losses, restarts and faults.
#include "broker_wire.hpp"

#include <linux/can/error.h>

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

#include "canhil/frames/wire.hpp"
#include "canhil/userbus/state.hpp"
#include "canhil/wire/wire_fault.hpp"

namespace {

namespace ub = canhil::userbus;
namespace frames = canhil::frames;

constexpr std::int64_t kT0 = 5'000'000'000;  // the broker's monotonic clock at the wire's start
constexpr std::int32_t kIndex = ub::kFirstIndex;

ub::TxRecord record(canid_t id, std::uint8_t len) {
  ub::TxRecord r{};
  r.ifindex = kIndex;
  r.size = CAN_MTU;
  can_frame f{};
  f.can_id = id;
  f.len = len;
  for (std::uint8_t k = 0; k < len; ++k) f.data[k] = static_cast<std::uint8_t>(0x11 * k);
  std::memcpy(r.frame, &f, sizeof f);
  return r;
}

canid_t id_of(const ub::WireDelivery& d) {
  canid_t id = 0;
  std::memcpy(&id, d.frame, sizeof id);
  return id;
}

// A frame's wire time at 1 Mbit/s, in ns, intermission included.
std::int64_t wire_ns(canid_t id, std::uint8_t len) {
  frames::WireFrame w;
  w.id = id;
  w.len = len;
  for (std::uint8_t k = 0; k < len; ++k) w.data[k] = static_cast<std::uint8_t>(0x11 * k);
  return static_cast<std::int64_t>(frames::count_bits(w).total()) * 1000;
}

class BrokerWireTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ub::Interface& i = state_->interfaces[0];
    i.index = kIndex;
    std::strcpy(i.name, "vcan0");
    i.up.store(1);
    i.bit_rate.store(1'000'000);
    i.restart_ms.store(100);
    i.tx_queue.store(10);
    i.in_use.store(1);
    wire_.sync(kT0);
  }
  ub::Controller& row(std::int32_t pid) { return *ub::find_controller(*state_, pid, kIndex, -1, false); }
  // What the preload does before it hands a frame over: one more in its queue.
  void give(std::int32_t pid, std::uint64_t tag, const ub::TxRecord& r, std::int64_t at) {
    ub::find_controller(*state_, pid, kIndex, -1, true)->queued.fetch_add(1);
    wire_.submit(ub::ControllerKey{pid, -1}, tag, r, at, out_);
  }
  std::unique_ptr<ub::State> state_ = std::make_unique<ub::State>();
  ub::BrokerWire wire_{*state_};
  std::vector<ub::WireDelivery> out_;
};

TEST_F(BrokerWireTest, FramesComeBackAtTheirEndOfFrameInTheOrderArbitrationGives) {
  EXPECT_TRUE(wire_.timed(kIndex));
  EXPECT_FALSE(wire_.timed(kIndex + 1));
  wire_.join(ub::ControllerKey{200, -1}, kIndex);  // a receiver, so the frames are acknowledged
  give(100, 1, record(0x300, 8), kT0);
  give(100, 2, record(0x200, 2), kT0 + 1000);  // waits behind its own first frame
  give(200, 3, record(0x100, 4), kT0 + 2000);  // another controller's, lower id: wins the next arbitration
  EXPECT_EQ(row(100).queued.load(), 2U);
  EXPECT_EQ(wire_.next_due(), kT0 + wire_ns(0x300, 8) - 3000) << "the first frame's end of frame";
  wire_.advance(kT0 + 10'000'000, out_);
  ASSERT_EQ(out_.size(), 3U);
  EXPECT_EQ(id_of(out_[0]), 0x300U);
  EXPECT_EQ(id_of(out_[1]), 0x100U);
  EXPECT_EQ(id_of(out_[2]), 0x200U);
  // Each frame starts 3 bits after the last one's end of frame: its own bits later.
  EXPECT_EQ(out_[0].at_ns, kT0 + wire_ns(0x300, 8) - 3000);
  EXPECT_EQ(out_[1].at_ns - out_[0].at_ns, wire_ns(0x100, 4));
  EXPECT_EQ(out_[2].at_ns - out_[1].at_ns, wire_ns(0x200, 2));
  EXPECT_EQ(out_[0].from.pid, 100);
  EXPECT_EQ(out_[0].tag, 1U);
  EXPECT_EQ(out_[1].from.pid, 200);
  EXPECT_EQ(std::memcmp(out_[2].frame, record(0x200, 2).frame, CAN_MTU), 0) << "the frame as the program wrote it";
  EXPECT_EQ(row(100).queued.load(), 0U) << "room again in the queue the preload counts";
  EXPECT_EQ(row(100).sent.load(), 2U);
  EXPECT_EQ(row(200).received.load(), 2U);
  EXPECT_EQ(wire_.next_due(), INT64_MAX);
  EXPECT_GT(state_->interfaces[0].busy_ns.load(), 0U);
}

TEST_F(BrokerWireTest, ALoneSenderGetsAckErrorsAndStaysErrorPassive) {
  // ISO 11898-1:2015 12.1.4.2 rule 3, exception 1: an error-passive
  // transmitter's ACK error does not count, so it never goes bus-off.
  give(100, 1, record(0x123, 1), kT0);
  wire_.advance(kT0 + 50'000'000, out_);
  ASSERT_FALSE(out_.empty());
  std::size_t acks = 0;
  for (const ub::WireDelivery& d : out_) {
    ASSERT_TRUE(d.error);
    EXPECT_EQ(d.from.pid, 100);
    EXPECT_NE(id_of(d) & CAN_ERR_FLAG, 0U);
    if ((id_of(d) & CAN_ERR_ACK) != 0) ++acks;
  }
  EXPECT_GT(acks, 16U);
  EXPECT_EQ(row(100).state.load(), 2U) << "error-passive";
  EXPECT_EQ(row(100).tec.load(), 128U);
  EXPECT_EQ(row(100).bus_offs.load(), 0U);
  EXPECT_EQ(row(100).queued.load(), 1U) << "still trying";
}

TEST_F(BrokerWireTest, AForcedBusOffLosesTheFrameOnTheWireAndRestartsOnRequest) {
  state_->interfaces[0].restart_ms.store(0);  // as the kernel's restart-ms 0: only on request
  wire_.sync(kT0);
  wire_.join(ub::ControllerKey{200, -1}, kIndex);
  EXPECT_EQ(wire_.restart(kIndex, 0, kT0), -EBUSY) << "nobody is bus-off";
  give(100, 1, record(0x123, 8), kT0);
  give(100, 2, record(0x124, 8), kT0);
  ub::FaultRequest busoff{};
  busoff.kind = static_cast<std::uint32_t>(canhil::wire::FaultRule::Kind::kBusOff);
  busoff.from_ns = 20'000;  // in the middle of the first frame
  busoff.until_ns = -1;
  busoff.pid = 100;
  busoff.slot = -1;
  ASSERT_EQ(wire_.add_fault(kIndex, busoff, kT0), 0);
  busoff.pid = 999;
  EXPECT_EQ(wire_.add_fault(kIndex, busoff, kT0), -ESRCH) << "no such controller";
  wire_.advance(kT0 + 500'000'000, out_);
  EXPECT_EQ(row(100).state.load(), 3U) << "bus-off";
  EXPECT_EQ(row(100).queued.load(), 1U) << "the frame on the wire lost, the next one kept";
  for (const ub::WireDelivery& d : out_) EXPECT_TRUE(d.error) << "nothing sent while bus-off";
  ASSERT_EQ(wire_.restart(kIndex, 0, kT0 + 500'000'000), 0);
  out_.clear();
  wire_.advance(kT0 + 510'000'000, out_);
  EXPECT_EQ(row(100).state.load(), 0U);
  EXPECT_EQ(row(100).restarts.load(), 1U);
  bool restarted = false;
  bool sent = false;
  for (const ub::WireDelivery& d : out_) {
    if (d.error && (id_of(d) & CAN_ERR_RESTARTED) != 0) restarted = true;
    if (!d.error && id_of(d) == 0x124U) sent = true;
  }
  EXPECT_TRUE(restarted);
  EXPECT_TRUE(sent);
  EXPECT_EQ(row(100).queued.load(), 0U);
}

TEST_F(BrokerWireTest, AControllerWhoseProcessEndedSendsWhatItHeldThenLeaves) {
  wire_.join(ub::ControllerKey{200, -1}, kIndex);
  give(100, 1, record(0x10, 8), kT0);
  give(100, 2, record(0x11, 8), kT0);
  wire_.leave(ub::ControllerKey{100, -1});
  EXPECT_NE(ub::find_controller(*state_, 100, kIndex, -1, false), nullptr);
  wire_.advance(kT0 + 10'000'000, out_);
  ASSERT_EQ(out_.size(), 2U);
  EXPECT_EQ(ub::find_controller(*state_, 100, kIndex, -1, false), nullptr) << "gone once its queue is empty";
}

TEST_F(BrokerWireTest, AControllerThatCanNeverSendLeavesWithItsProcessAndOneThatComesBackStays) {
  give(100, 1, record(0x10, 8), kT0);  // alone: never acknowledged
  wire_.advance(kT0 + 5'000'000, out_);
  wire_.leave(ub::ControllerKey{100, -1});
  wire_.advance(kT0 + 6'000'000, out_);
  EXPECT_EQ(ub::find_controller(*state_, 100, kIndex, -1, false), nullptr)
      << "an unacknowledged lone sender whose process ended does not retry for ever";
  wire_.join(ub::ControllerKey{200, -1}, kIndex);
  give(300, 2, record(0x20, 8), kT0 + 7'000'000);
  wire_.leave(ub::ControllerKey{300, -1});
  wire_.join(ub::ControllerKey{300, -1}, kIndex);  // a socket of its own again before its queue emptied
  wire_.advance(kT0 + 20'000'000, out_);
  EXPECT_NE(ub::find_controller(*state_, 300, kIndex, -1, false), nullptr) << "it came back: it stays";
}

TEST_F(BrokerWireTest, AProcessThatClosedItsSocketAndOpensAnotherHearsTheWireAgain) {
  // Its old controller left the bus; the new one has the same key (the
  // process). The old one is no longer on the bus: it must not make the new
  // one miss every frame (it did: a handler that reopened its socket was deaf).
  wire_.join(ub::ControllerKey{200, -1}, kIndex);
  give(100, 1, record(0x10, 8), kT0);
  wire_.advance(kT0 + 1'000'000, out_);
  wire_.leave(ub::ControllerKey{200, -1});  // its socket closed
  wire_.advance(kT0 + 2'000'000, out_);
  EXPECT_EQ(ub::find_controller(*state_, 200, kIndex, -1, false), nullptr) << "it left";
  wire_.join(ub::ControllerKey{200, -1}, kIndex);  // a new socket of the same process
  out_.clear();
  give(100, 2, record(0x11, 8), kT0 + 3'000'000);
  wire_.advance(kT0 + 10'000'000, out_);
  ASSERT_EQ(out_.size(), 1U);
  EXPECT_FALSE(out_[0].error) << "acknowledged";
  EXPECT_TRUE(out_[0].missed.empty()) << "the process's new controller got it";
  EXPECT_EQ(row(200).received.load(), 1U);
}

TEST_F(BrokerWireTest, AFaultThatNeedsANodeAndNamesNoneIsRefused) {
  ub::FaultRequest f{};
  f.kind = static_cast<std::uint32_t>(canhil::wire::FaultRule::Kind::kBusOff);
  f.until_ns = -1;
  f.slot = -1;
  EXPECT_EQ(wire_.add_fault(kIndex, f, kT0), -EINVAL) << "bus-off of nobody";
  f.kind = static_cast<std::uint32_t>(canhil::wire::FaultRule::Kind::kNoAck);
  f.from_ns = INT64_MAX;  // far beyond any run: clamped, no overflow
  EXPECT_EQ(wire_.add_fault(kIndex, f, kT0), 0);
  f.kind = 99;
  EXPECT_EQ(wire_.add_fault(kIndex, f, kT0), -EINVAL);
}

TEST_F(BrokerWireTest, ANewBitRateIsANewWireAndZeroIsNone) {
  give(100, 1, record(0x10, 8), kT0);
  state_->interfaces[0].bit_rate.store(500'000);
  wire_.sync(kT0 + 1000);
  EXPECT_TRUE(wire_.timed(kIndex));
  EXPECT_EQ(ub::find_controller(*state_, 100, kIndex, -1, false), nullptr)
      << "its controllers and what waited on the old wire go with it, as on a link set down";
  state_->interfaces[0].bit_rate.store(0);
  wire_.sync(kT0 + 2000);
  EXPECT_FALSE(wire_.timed(kIndex));
  EXPECT_EQ(wire_.restart(kIndex, 0, kT0), -EINVAL);
}

}  // namespace
