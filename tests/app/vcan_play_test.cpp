// `canhil play` on a real vcan: every frame of a recorded bus back on the
// interface, in the recorded order, at any speed; interfaces mapped; a loop
// goes round until Ctrl-C. Order and counts only: timing inside the VM runner
// is not a measurement.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/frames/candump.hpp"
#include "support/child_process.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;
using canhil::can_nodes::SocketCanBus;

// 40 frames, 2 ms apart: ids 0x200.. from vcan0 and every fifth from vcan1.
std::string write_trace() {
  std::string path = "/tmp/canhil_vcan_play_trace.log";
  std::ofstream out(path);
  for (int i = 0; i < 40; ++i) {
    canhil::frames::CanFrame f{static_cast<std::uint32_t>(0x200 + i), false};
    f.len = 2;
    f.data[0] = static_cast<std::uint8_t>(i);
    f.data[1] = 0xAB;
    out << canhil::frames::format_log_line(std::chrono::seconds(1'700'000'000) + i * 2ms,
                                           i % 5 == 4 ? "vcan1" : "vcan0", f)
        << '\n';
  }
  return path;
}

std::vector<canhil::frames::CanFrame> drain(SocketCanBus& bus, std::size_t want, std::chrono::seconds limit) {
  std::vector<canhil::frames::CanFrame> got;
  const auto until = std::chrono::steady_clock::now() + limit;
  while (got.size() < want && std::chrono::steady_clock::now() < until) {
    if (auto f = bus.receive()) {
      got.push_back(f->frame);
    } else {
      std::this_thread::sleep_for(1ms);
    }
  }
  return got;
}

std::string canhil_play(const std::string& args) { return canhil::test::build_dir() + "/app/canhil play " + args; }

bool ended(const canhil::test::ChildProcess& p, std::chrono::seconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (p.output().find("canhil play: done") == std::string::npos) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(50ms);
  }
  return true;
}

TEST(VcanPlay, EveryFrameComesBackInOrderAtTheSpeedAsked) {
  const std::string trace = write_trace();
  auto bus = SocketCanBus::open("vcan0");
  canhil::test::ChildProcess play(canhil_play(trace + " --iface vcan0 --speed 4"), "/tmp/canhil_vcan_play.log");
  const auto got = drain(*bus, 40, 60s);
  const std::optional<int> status = play.wait_end(60s);  // it ends by itself once done
  ASSERT_TRUE(status.has_value()) << play.output();
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << play.output();
  ASSERT_EQ(got.size(), 40u) << play.output();
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].id, 0x200 + i);
    EXPECT_EQ(got[i].data[0], i);
    EXPECT_EQ(got[i].data[1], 0xAB);
  }
  EXPECT_NE(play.output().find("40 frame(s) sent in 1 pass(es)"), std::string::npos) << play.output();
}

TEST(VcanPlay, MappedInterfacesOnlyAndALoopGoesRoundUntilCtrlC) {
  const std::string trace = write_trace();
  auto bus1 = SocketCanBus::open("vcan1");
  {
    // Only what was recorded on vcan1, onto vcan1: 8 frames, 32 not mapped.
    canhil::test::ChildProcess play(canhil_play(trace + " --map vcan1=vcan1 --speed 8"),
                                    "/tmp/canhil_vcan_play_map.log");
    const auto got = drain(*bus1, 8, 60s);
    ASSERT_TRUE(ended(play, 60s)) << play.output();
    play.stop();
    ASSERT_EQ(got.size(), 8u);
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].id, 0x200 + 5 * i + 4);
    EXPECT_NE(play.output().find("32 not mapped"), std::string::npos) << play.output();
  }
  auto bus0 = SocketCanBus::open("vcan0");
  canhil::test::ChildProcess loop(canhil_play(trace + " --iface vcan0 --speed 8 --loop"),
                                  "/tmp/canhil_vcan_play_loop.log");
  const auto got = drain(*bus0, 100, 90s);
  const int status = loop.stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << loop.output();
  ASSERT_EQ(got.size(), 100u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].id, 0x200 + i % 40) << i;
}

}  // namespace
