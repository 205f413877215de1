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

// Drains `fence` until it counts `want` frames on interface 0 (or 5 s pass).
bool wait_delivered(DeliveryFence& fence, std::uint64_t want) {
  const auto until = std::chrono::steady_clock::now() + 5s;
  for (;;) {
    fence.drain();
    if (fence.delivered(0) >= want) return true;
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::yield();
  }
}

std::size_t read_all(SocketCanBus& bus) {
  std::size_t n = 0;
  while (bus.receive()) ++n;
  return n;
}

TEST(DeliveryFence, CountsStandardDataFramesOnlyOfItsOwnInterface) {
  DeliveryFence fence;
  ASSERT_EQ(fence.add("vcan0"), 0u);
  ASSERT_EQ(fence.add("vcan1"), 1u);
  auto sender = SocketCanBus::open("vcan0");
  ASSERT_EQ(sender->send(make_data_frame(0x000, {1})), SendStatus::kOk);
  ASSERT_EQ(sender->send(make_data_frame(0x7FF, {2})), SendStatus::kOk);
  frames::CanFrame extended = make_data_frame(0x12345, {3});
  extended.extended = true;
  frames::CanFrame remote = make_data_frame(0x123, {});
  remote.kind = frames::FrameKind::kRemote;
  ASSERT_EQ(sender->send(extended), SendStatus::kOk);
  ASSERT_EQ(sender->send(remote), SendStatus::kOk);
  ASSERT_EQ(sender->send(make_data_frame(0x200, {4})), SendStatus::kOk);
  ASSERT_TRUE(wait_delivered(fence, 3));
  std::this_thread::sleep_for(50ms);  // nothing more comes
  fence.drain();
  EXPECT_EQ(fence.delivered(0), 3u) << "ids 0x000, 0x7FF and 0x200, each once";
  EXPECT_EQ(fence.delivered(1), 0u) << "vcan1 carried nothing";
  EXPECT_TRUE(DeliveryFence::counts(make_data_frame(0x7FF, {})));
  EXPECT_FALSE(DeliveryFence::counts(extended));
  EXPECT_FALSE(DeliveryFence::counts(remote));
}

TEST(DeliveryFence, OnceTheFenceHasAFrameEverySocketHasIt) {
  // Sockets of each kind the kernel keeps in its own list, all opened after
  // the fence: no filter, a mask filter, an inverted filter, a single id.
  DeliveryFence fence;
  fence.add("vcan0");
  SocketCanOptions options;
  options.receive_buffer_bytes = 1 << 22;
  std::vector<std::unique_ptr<SocketCanBus>> receivers;
  receivers.push_back(SocketCanBus::open("vcan0", options));
  Filter mask{0x100, 0x700};
  Filter inverted{0x0FF, frames::kStandardIdMask};
  inverted.invert = true;
  for (const Filter& f : {mask, inverted, Filter::exact(0x123)}) {
    options.filters = {f};
    receivers.push_back(SocketCanBus::open("vcan0", options));
  }
  // Another thread sends, so that the kernel's delivery may run on the other core.
  constexpr int kBursts = 3000;
  std::atomic<int> asked{0};
  std::atomic<int> done{0};
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
      done.store(b + 1);
    }
  });
  std::uint64_t total = 0;
  int late = 0;
  for (int b = 0; b < kBursts; ++b) {
    const int n = 1 + b % 4;
    total += static_cast<std::uint64_t>(n);
    asked.store(b + 1);
    ASSERT_TRUE(wait_delivered(fence, total)) << "burst " << b;
    // The fence has the burst: every receiver must have it too, right now.
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
