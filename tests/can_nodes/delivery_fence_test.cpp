// The delivery fence on a real vcan (run through vcan_setup/with-vcan.sh).
#include "canhil/can_nodes/delivery_fence.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"

namespace canhil::can_nodes {
namespace {

using frames::make_data_frame;
using namespace std::chrono_literals;

// Reads `observer` and drains `fence` until the fence says the first `want`
// fenced frames on interface 0 are in every socket (or 5 s pass).
bool wait_reached(DeliveryFence& fence, SocketCanBus& observer, std::uint64_t& fenced, std::uint64_t want) {
  const auto until = std::chrono::steady_clock::now() + 5s;
  for (;;) {
    while (auto f = observer.receive()) {
      if (DeliveryFence::counts(f->frame)) ++fenced;
    }
    fence.drain();
    if (fenced >= want && fence.reached(0, fenced)) return true;
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::yield();
  }
}

std::size_t read_all(SocketCanBus& bus) {
  std::size_t n = 0;
  while (bus.receive()) ++n;
  return n;
}

TEST(DeliveryFence, FencesStandardDataFramesOnly) {
  EXPECT_TRUE(DeliveryFence::counts(make_data_frame(0x000, {})));
  EXPECT_TRUE(DeliveryFence::counts(make_data_frame(0x7FF, {1, 2})));
  frames::CanFrame extended = make_data_frame(0x12345, {3});
  extended.extended = true;
  frames::CanFrame remote = make_data_frame(0x123, {});
  remote.kind = frames::FrameKind::kRemote;
  EXPECT_FALSE(DeliveryFence::counts(extended));
  EXPECT_FALSE(DeliveryFence::counts(remote));
}

TEST(DeliveryFence, OnTheKernelItCountsItsOwnInterfaceOnTheUserSpaceBusTheBusTells) {
  DeliveryFence fence;
  ASSERT_EQ(fence.add("vcan0"), 0u);
  ASSERT_EQ(fence.add("vcan1"), 1u);
  const bool bus_tells = on_user_space_bus("vcan0");
  EXPECT_EQ(fence.sockets(0), bus_tells ? 0u : 4u) << "four sockets of 512 single-id filters on the kernel's";
  EXPECT_EQ(fence.sockets(1), bus_tells ? 0u : 4u);
  auto observer = SocketCanBus::open("vcan0");
  auto sender = SocketCanBus::open("vcan0");
  ASSERT_EQ(sender->send(make_data_frame(0x000, {1})), SendStatus::kOk);
  ASSERT_EQ(sender->send(make_data_frame(0x7FF, {2})), SendStatus::kOk);
  frames::CanFrame extended = make_data_frame(0x12345, {3});
  extended.extended = true;
  ASSERT_EQ(sender->send(extended), SendStatus::kOk);
  ASSERT_EQ(sender->send(make_data_frame(0x200, {4})), SendStatus::kOk);
  std::uint64_t fenced = 0;
  ASSERT_TRUE(wait_reached(fence, *observer, fenced, 3));
  std::this_thread::sleep_for(50ms);  // nothing more comes
  EXPECT_EQ(read_all(*observer), 0u);
  EXPECT_EQ(fenced, 3u) << "ids 0x000, 0x7FF and 0x200, each once";
  fence.drain();
  EXPECT_TRUE(fence.reached(0, 3));
  // On the kernel's, the fence counts what its sockets read: a fourth frame
  // it never saw has not reached it (the bus's tells of rounds, not counts).
  if (!bus_tells) {
    EXPECT_FALSE(fence.reached(0, 4));
    EXPECT_FALSE(fence.reached(1, 1)) << "vcan0's frames are not vcan1's";
  }
}

TEST(DeliveryFence, OnceTheFenceSaysSoEverySocketHasTheFrames) {
  // Sockets of each kind the kernel keeps in its own list, all opened after
  // the fence: no filter, a mask filter, an inverted filter, and many with a
  // single id, served last; then the socket the frames are read on first, as
  // canhil's own: with no filter and opened last, it is served first, so the
  // others get each frame after it, later by a dozen hand-overs.
  DeliveryFence fence;
  fence.add("vcan0");
  SocketCanOptions options;
  options.receive_buffer_bytes = 1 << 22;
  std::vector<std::unique_ptr<SocketCanBus>> receivers;
  receivers.push_back(SocketCanBus::open("vcan0", options));
  Filter mask{0x100, 0x700};
  Filter inverted{0x0FF, frames::kStandardIdMask};
  inverted.invert = true;
  for (const Filter& f : {mask, inverted}) {
    options.filters = {f};
    receivers.push_back(SocketCanBus::open("vcan0", options));
  }
  options.filters = {Filter::exact(0x123)};
  for (int k = 0; k < 12; ++k) receivers.push_back(SocketCanBus::open("vcan0", options));
  options.filters.clear();
  auto observer = SocketCanBus::open("vcan0", options);
  // Another thread sends, so that the delivery may run on the other core.
  constexpr int kBursts = 3000;
  std::atomic<int> asked{0};
  std::thread sender_thread([&] {
    auto sender = SocketCanBus::open("vcan0");
    for (int b = 0; b < kBursts; ++b) {
      while (asked.load() == b) std::this_thread::yield();
      const int n = 1 + b % 4;
      for (int i = 0; i < n; ++i) {
        while (sender->send(make_data_frame(0x123, {static_cast<std::uint8_t>(i)})) != SendStatus::kOk) {
          std::this_thread::yield();
        }
      }
    }
  });
  std::uint64_t total = 0;
  std::uint64_t fenced = 0;
  int late = 0;
  for (int b = 0; b < kBursts; ++b) {
    const int n = 1 + b % 4;
    total += static_cast<std::uint64_t>(n);
    asked.store(b + 1);
    ASSERT_TRUE(wait_reached(fence, *observer, fenced, total)) << "burst " << b;
    // The fence says the burst is delivered: every receiver must have it, right now.
    for (auto& r : receivers) {
      const std::size_t got = read_all(*r);
      if (got != static_cast<std::size_t>(n)) ++late;
      EXPECT_EQ(got, static_cast<std::size_t>(n)) << "burst " << b << " on a socket after the fence";
    }
    if (late > 10) break;
  }
  asked.store(kBursts + 1);
  sender_thread.join();
  EXPECT_EQ(late, 0);
}

}  // namespace
}  // namespace canhil::can_nodes
