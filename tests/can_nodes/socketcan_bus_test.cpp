// SocketCAN backend on a real vcan. Run through vcan_setup/with-vcan.sh
// (--ifaces 2): on this project's machines that is inside the VM runner.
// Nothing here skips: a missing vcan0 fails the suite with the set-up error.
#include "canhil/can_nodes/socketcan_bus.hpp"

#include <gtest/gtest.h>
#include <net/if.h>
#include <sys/ioctl.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <thread>

#include "canhil/can_nodes/clock.hpp"
#include "support/test_paths.hpp"

namespace canhil::can_nodes {
namespace {

using frames::make_data_frame;
using namespace std::chrono_literals;

// Receives until `want` frames arrived or were counted as dropped, or 2 s of
// no traffic (bounded, never hangs).
std::vector<TimedFrame> receive_n(SocketCanBus& bus, std::size_t want) {
  std::vector<TimedFrame> got;
  while (got.size() < want) {
    if (auto f = bus.receive()) {
      got.push_back(*f);
      continue;
    }
    if (got.size() + bus.stats().rx_overflow >= want) break;
    if (!bus.wait_readable(2s)) break;
  }
  return got;
}

int sh(const std::string& command) { return std::system(command.c_str()); }

TEST(SocketCan, KernelHasCan) { ASSERT_TRUE(kernel_has_can()) << "run this suite through vcan_setup/with-vcan.sh"; }

TEST(SocketCan, TwoSocketsSeeEachOthersFramesWithKernelTimestamps) {
  auto a = SocketCanBus::open("vcan0");
  auto b = SocketCanBus::open("vcan0");
  const WallClock wall;
  const Nanos before = wall.now();
  ASSERT_EQ(a->send(make_data_frame(0x131, {0xF4, 0x01, 0, 0, 0, 0, 0, 0})), SendStatus::kOk);
  ASSERT_EQ(b->send(make_data_frame(0x122, {1})), SendStatus::kOk);
  const auto at_b = receive_n(*b, 1);
  const auto at_a = receive_n(*a, 1);
  const Nanos after = wall.now();
  ASSERT_EQ(at_b.size(), 1u);
  ASSERT_EQ(at_a.size(), 1u);
  EXPECT_EQ(at_b[0].frame, make_data_frame(0x131, {0xF4, 0x01, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(at_a[0].frame, make_data_frame(0x122, {1}));
  EXPECT_GE(at_b[0].time, before);
  EXPECT_LE(at_b[0].time, after);
  EXPECT_FALSE(a->receive()) << "own frames are not received by default";
  EXPECT_EQ(a->stats().sent, 1u);
  EXPECT_EQ(b->stats().received, 1u);
}

TEST(SocketCan, ExtendedRemoteAndDlcFramesSurviveTheKernel) {
  auto a = SocketCanBus::open("vcan0");
  auto b = SocketCanBus::open("vcan0");
  frames::CanFrame ext = make_data_frame(0x1ABCDE12, {9, 8, 7});
  ext.extended = true;
  frames::CanFrame rtr;
  rtr.id = 0x321;
  rtr.kind = frames::FrameKind::kRemote;
  rtr.len = 4;
  ASSERT_EQ(a->send(ext), SendStatus::kOk);
  ASSERT_EQ(a->send(rtr), SendStatus::kOk);
  const auto got = receive_n(*b, 2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame, ext);
  EXPECT_EQ(got[1].frame, rtr);
}

TEST(SocketCan, KernelFiltersPassOnlyWhatWasAskedFor) {
  auto tx = SocketCanBus::open("vcan0");
  auto rx = SocketCanBus::open("vcan0");
  const Filter filters[] = {Filter::exact(0x131), Filter{0x110, 0x7F0, false, false, false, false, false}};
  rx->set_filters(filters);
  for (std::uint32_t id : {0x100u, 0x111u, 0x112u, 0x131u, 0x132u, 0x7FFu}) tx->send(make_data_frame(id, {}));
  tx->send(make_data_frame(0x131, {0xEE}));  // marks the end
  std::vector<std::uint32_t> got;
  for (const auto& f : receive_n(*rx, 4)) got.push_back(f.frame.id);
  EXPECT_EQ(got, (std::vector<std::uint32_t>{0x111, 0x112, 0x131, 0x131}));
}

TEST(SocketCan, AFedSocketTakesWhatItIsGivenAsTheKernelWould) {
  auto tx = SocketCanBus::open("vcan0");
  SocketCanOptions options;
  options.filters = {Filter::exact(0x131)};
  options.fed = true;
  auto rx = SocketCanBus::open("vcan0", options);
  auto listener = SocketCanBus::open("vcan0");
  const frames::CanFrame m6 = make_data_frame(0x131, {1});
  ASSERT_EQ(tx->send(m6), SendStatus::kOk);
  ASSERT_TRUE(listener->wait_readable(2s)) << "the frame is on the bus";
  EXPECT_FALSE(rx->wait_readable(50ms)) << "the kernel queues nothing on a fed socket";
  EXPECT_FALSE(rx->receive()) << "nothing fed yet";
  rx->feed(make_data_frame(0x132, {}));
  EXPECT_FALSE(rx->receive()) << "a frame its filter does not pass";
  rx->feed(m6);
  const auto got = rx->receive();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame, m6);
  EXPECT_FALSE(rx->receive()) << "empty again";
  // Its own frame comes back through the driver's socket: not given to it.
  const frames::CanFrame own = make_data_frame(0x131, {2});
  ASSERT_EQ(rx->send(own), SendStatus::kOk);
  rx->feed(m6);  // another sender's frame, before its own on the bus
  rx->feed(own);
  rx->feed(own);  // the same frame again, from another sender
  std::vector<frames::CanFrame> taken;
  while (auto f = rx->receive()) taken.push_back(f->frame);
  EXPECT_EQ(taken, (std::vector<frames::CanFrame>{m6, own}));
  // Error frames by the error mask, as the kernel.
  rx->set_error_mask(0x4);
  frames::CanFrame error{};
  error.kind = frames::FrameKind::kError;
  error.id = 0x4;
  rx->feed(error);
  error.id = 0x8;
  rx->feed(error);
  const auto first = rx->receive();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame.id, 0x4u);
  EXPECT_FALSE(rx->receive()) << "an error class outside its mask";
  EXPECT_EQ(rx->stats().received, 3u);
  EXPECT_EQ(rx->stats().errors, 1u);
}

TEST(SocketCan, FiltersGivenAtOpenAreInPlaceBeforeAnyFrameArrives) {
  auto tx = SocketCanBus::open("vcan0");
  // A sender busy before and while the socket opens: with the filters set
  // before bind, no other id is ever queued (set_filters() after open() lets
  // in what came in between).
  // Ordered by counts, not by a sleep: the noise is on the bus before the
  // socket opens and goes on after (a loaded machine may not run the thread
  // for a while).
  std::atomic<bool> stop{false};
  std::atomic<int> noise_sent{0};
  std::thread noise([&] {
    while (!stop) {
      tx->send(make_data_frame(0x100, {1}));
      ++noise_sent;
    }
  });
  while (noise_sent.load() == 0) std::this_thread::yield();
  SocketCanOptions options;
  options.filters = {Filter::exact(0x131)};
  auto rx = SocketCanBus::open("vcan0", options);
  const int at_open = noise_sent.load();
  while (noise_sent.load() < at_open + 100) std::this_thread::yield();
  stop = true;
  noise.join();
  tx->send(make_data_frame(0x131, {0xEE}));
  const auto got = receive_n(*rx, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].frame.id, 0x131u) << "the first frame queued is the one asked for";
  EXPECT_GT(tx->stats().sent, 1u) << "the noise was on the bus";
}

TEST(SocketCan, ErrorFramesReachOnlySocketsWhoseMaskAsks) {
  auto tx = SocketCanBus::open("vcan0");
  auto none = SocketCanBus::open("vcan0");
  auto controller = SocketCanBus::open("vcan0");
  auto bus_off_only = SocketCanBus::open("vcan0");
  controller->set_error_mask(frames::kErrorClassController | frames::kErrorClassBusOff);
  bus_off_only->set_error_mask(frames::kErrorClassBusOff);
  frames::CanFrame err;
  err.kind = frames::FrameKind::kError;
  err.id = frames::kErrorClassController;
  err.len = 8;
  ASSERT_EQ(tx->send(err), SendStatus::kOk);
  ASSERT_EQ(tx->send(make_data_frame(0x131, {})), SendStatus::kOk);  // marks the end
  const auto got = receive_n(*controller, 2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].frame.kind, frames::FrameKind::kError);
  EXPECT_EQ(got[0].frame.id, frames::kErrorClassController);
  EXPECT_EQ(controller->stats().errors, 1u);
  for (auto* other : {none.get(), bus_off_only.get()}) {
    const auto only = receive_n(*other, 1);
    ASSERT_EQ(only.size(), 1u);
    EXPECT_EQ(only[0].frame.id, 0x131u) << "the error frame must not pass this mask";
    EXPECT_EQ(other->stats().errors, 0u);
  }
}

TEST(SocketCan, DropsAfterTheLastFrameReadAreCountedWithoutTheCheckWhenEmptyToo) {
  // A receiver that reads nothing while 2000 frames come: its small buffer
  // overflows, and the drops come after the last frame queued, so no frame's
  // SO_RXQ_OVFL tells them. The lockstep's observers skip the drop counter at
  // each empty read (drops_when_empty); stats() still reads it.
  for (const bool when_empty : {true, false}) {
    SocketCanOptions options;
    options.receive_buffer_bytes = 4096;
    options.drops_when_empty = when_empty;
    auto tx = SocketCanBus::open("vcan0");
    auto rx = SocketCanBus::open("vcan0", options);
    for (int i = 0; i < 2000; ++i) {
      ASSERT_NE(tx->send(make_data_frame(0x100, {static_cast<std::uint8_t>(i)})), SendStatus::kDown);
    }
    // On the user-space bus the broker may still be routing the last frames
    // when the queue first reads empty: read until each is read or counted.
    std::size_t received = 0;
    BusStats st;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    do {
      while (rx->receive()) ++received;
      st = rx->stats();
    } while (received + st.rx_overflow < tx->stats().sent && std::chrono::steady_clock::now() < give_up);
    EXPECT_GT(st.rx_overflow, 0u) << "the buffer overflowed (drops_when_empty " << when_empty << ")";
    EXPECT_EQ(received + st.rx_overflow, tx->stats().sent) << "drops_when_empty " << when_empty;
  }
}

TEST(SocketCan, OnTheUserSpaceBusAReadItsCountsSayIsEmptyMakesNoSystemCall) {
  // The lockstep's observers (skips_empty_reads): on the user-space bus the
  // bus's counts say whether a frame waits; on the kernel's, nothing says, so
  // every read asks the kernel.
  SocketCanOptions options;
  options.skips_empty_reads = true;
  auto tx = SocketCanBus::open("vcan1");
  auto rx = SocketCanBus::open("vcan1", options);
  const bool counted = on_user_space_bus("vcan1");
  EXPECT_EQ(rx->waiting().has_value(), counted);
  EXPECT_FALSE(rx->receive());
  EXPECT_EQ(rx->empty_reads_skipped(), counted ? 1u : 0u);
  for (std::uint8_t i = 0; i < 3; ++i) ASSERT_EQ(tx->send(make_data_frame(0x321, {i})), SendStatus::kOk);
  // Read as they come, in order, none lost to a skipped read.
  std::vector<std::uint8_t> got;
  const auto give_up = std::chrono::steady_clock::now() + 5s;
  while (got.size() < 3 && std::chrono::steady_clock::now() < give_up) {
    if (auto f = rx->receive()) {
      got.push_back(f->frame.data[0]);
    } else {
      std::this_thread::yield();
    }
  }
  EXPECT_EQ(got, (std::vector<std::uint8_t>{0, 1, 2}));
  if (counted) {
    EXPECT_EQ(rx->waiting(), std::optional<bool>(false)) << "all three read";
    const std::uint64_t skipped = rx->empty_reads_skipped();
    EXPECT_FALSE(rx->receive());
    EXPECT_EQ(rx->empty_reads_skipped(), skipped + 1);
    // Whether the counts come to say that something waits (before the give-up time).
    const auto comes_to_wait = [&] {
      while (rx->waiting() != std::optional<bool>(true) && std::chrono::steady_clock::now() < give_up) {
        std::this_thread::yield();
      }
      return rx->waiting() == std::optional<bool>(true);
    };
    // A frame counted as waiting is there to read.
    ASSERT_EQ(tx->send(make_data_frame(0x321, {3})), SendStatus::kOk);
    ASSERT_TRUE(comes_to_wait());
    const auto f = rx->receive();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame.data[0], 3);
    EXPECT_EQ(rx->waiting(), std::optional<bool>(false));
    // The bus's errors are counted too: an interface taken down (as `ip
    // link set vcan1 down`) is a record to read, ENETDOWN.
    const auto set_up = [&](bool up) {
      ifreq r{};
      std::snprintf(r.ifr_name, sizeof r.ifr_name, "vcan1");
      r.ifr_flags = static_cast<short>(up ? IFF_UP : 0);
      return ::ioctl(tx->fd(), SIOCSIFFLAGS, &r);
    };
    ASSERT_EQ(set_up(false), 0);
    struct BackUp {  // vcan1 up again however this test ends: the suite goes on on it
      std::function<int(bool)> set;
      ~BackUp() { set(true); }
    } back_up{set_up};
    EXPECT_TRUE(comes_to_wait());
    EXPECT_FALSE(rx->receive());
    EXPECT_EQ(rx->state(), BusState::kDown);
    EXPECT_EQ(rx->waiting(), std::optional<bool>(false));
  }
}

TEST(SocketCan, TimestampsAreMonotonic) {
  auto tx = SocketCanBus::open("vcan0");
  auto rx = SocketCanBus::open("vcan0");
  for (int i = 0; i < 2000; ++i) {
    ASSERT_EQ(tx->send(make_data_frame(0x100, {static_cast<std::uint8_t>(i)})), SendStatus::kOk);
    if (i % 100 == 99) std::this_thread::yield();
  }
  const auto got = receive_n(*rx, 2000);
  ASSERT_EQ(got.size() + rx->stats().rx_overflow, 2000u);
  for (std::size_t i = 1; i < got.size(); ++i) ASSERT_GE(got[i].time, got[i - 1].time) << i;
}

TEST(SocketCan, HundredThousandFramesAtFullSpeedAreAllReceivedOrCounted) {
  constexpr std::uint64_t kFrames = 100'000;
  auto tx = SocketCanBus::open("vcan0");
  SocketCanOptions rx_options;
  rx_options.receive_buffer_bytes = 4 << 20;
  auto rx = SocketCanBus::open("vcan0", rx_options);
  std::atomic<bool> done{false};
  std::uint64_t received = 0;
  std::uint32_t expected_seq = 0;
  std::uint64_t gaps = 0;
  std::thread reader([&] {
    while (true) {
      while (auto f = rx->receive()) {
        std::uint32_t seq = 0;
        std::memcpy(&seq, f->frame.data.data(), 4);
        if (seq != expected_seq) ++gaps;
        expected_seq = seq + 1;
        ++received;
      }
      if (done.load() && !rx->wait_readable(500ms)) break;
      rx->wait_readable(50ms);
    }
  });
  for (std::uint32_t i = 0; i < kFrames; ++i) {
    frames::CanFrame f = make_data_frame(0x200, {0, 0, 0, 0, 0, 0, 0, 0});
    std::memcpy(f.data.data(), &i, 4);
    tx->send(f);  // full speed: no pacing
  }
  done = true;
  reader.join();
  const BusStats t = tx->stats();
  const BusStats r = rx->stats();
  std::printf("100k at full speed: sent %llu, send-dropped %llu, retries %llu; received %llu, overflow %llu\n",
              static_cast<unsigned long long>(t.sent), static_cast<unsigned long long>(t.send_dropped),
              static_cast<unsigned long long>(t.send_retries), static_cast<unsigned long long>(received),
              static_cast<unsigned long long>(r.rx_overflow));
  EXPECT_EQ(t.sent + t.send_dropped, kFrames) << "every frame was sent or its drop counted";
  EXPECT_EQ(received + r.rx_overflow, t.sent) << "every sent frame was received or its loss counted";
  EXPECT_EQ(received, r.received);
  if (r.rx_overflow == 0 && t.send_dropped == 0) {
    EXPECT_EQ(gaps, 0u) << "no loss, so no gap in the sequence";
  }
}

TEST(SocketCan, InterfaceDownAndUpIsReportedAndSendsResume) {
  auto a = SocketCanBus::open("vcan1");
  auto b = SocketCanBus::open("vcan1");
  ASSERT_EQ(a->state(), BusState::kUp);
  ASSERT_EQ(sh("ip link set vcan1 down"), 0);
  EXPECT_EQ(a->send(make_data_frame(0x10, {})), SendStatus::kDown);
  EXPECT_EQ(a->state(), BusState::kDown);
  EXPECT_EQ(b->refresh_state(), BusState::kDown);
  ASSERT_EQ(sh("ip link set vcan1 up"), 0);
  EXPECT_EQ(a->refresh_state(), BusState::kUp);
  EXPECT_EQ(a->send(make_data_frame(0x11, {})), SendStatus::kOk);
  const auto got = receive_n(*b, 1);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].frame.id, 0x11u) << "no stale frame from while it was down";
  EXPECT_GE(a->stats().state_changes, 2u);
}

TEST(SocketCan, VanishedInterfaceIsReportedNotHung) {
  ASSERT_EQ(sh("ip link add dev vcangone type vcan && ip link set vcangone up"), 0);
  auto a = SocketCanBus::open("vcangone");
  ASSERT_EQ(sh("ip link del dev vcangone"), 0);
  EXPECT_EQ(a->refresh_state(), BusState::kGone);
  EXPECT_NE(a->send(make_data_frame(0x10, {})), SendStatus::kOk);
  EXPECT_FALSE(a->receive());
  EXPECT_FALSE(a->wait_readable(10ms) && a->receive());
}

TEST(SocketCan, MissingInterfaceIsASetUpErrorThatSaysWhatToDo) {
  try {
    SocketCanBus::open("vcan9");
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("vcan-up.sh vcan9"), std::string::npos) << e.what();
  }
}

// `canhil dump` decodes frames sent by can-utils' cansend.
TEST(SocketCan, CanhilDumpDecodesFramesFromCansend) {
  ASSERT_EQ(sh("command -v cansend >/dev/null"), 0) << "can-utils is not installed (scripts/install-deps.sh)";
  const std::string cmd = test::canhil_binary() + " dump vcan0 --count 2 --seconds 30 2>/dev/null";
  FILE* dump = popen(cmd.c_str(), "r");
  ASSERT_NE(dump, nullptr);
  std::atomic<bool> stop{false};
  std::thread sender([&] {
    // Until dump has what it needs (it may not be listening yet at first).
    while (!stop) {
      sh("cansend vcan0 131#F401000000000000; cansend vcan0 7FF#DEAD");
      std::this_thread::sleep_for(50ms);
    }
  });
  std::string out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, dump) != nullptr) out += buf;
  pclose(dump);
  stop = true;
  sender.join();
  EXPECT_NE(out.find("vcan0 131#F401000000000000"), std::string::npos) << out;
  EXPECT_NE(out.find("M6_1  vx=0.500 m/s  vy=0.000 m/s"), std::string::npos) << out;
  EXPECT_NE(out.find("7FF#DEAD"), std::string::npos) << out;
  EXPECT_NE(out.find("[unknown id]"), std::string::npos) << out;
}

}  // namespace
}  // namespace canhil::can_nodes
