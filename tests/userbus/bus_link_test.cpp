// Timed interfaces of the user-space bus (userbus/src/bus_link.cpp, the
// broker's wire) with real, unchanged programs: can-utils and python-can on
// a wire with its bit rate, its transmit queues, its errors and bus-off.
// Wall-clock figures are not asserted: the stamps are the model's (each
// frame's end of frame), so what is checked is exact whatever the load.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "bus_support.hpp"
#include "canhil/frames/wire.hpp"
#include "canhil/userbus/bus.hpp"
#include "support/test_paths.hpp"

namespace {

namespace ub = canhil::userbus;
namespace frames = canhil::frames;
using canhil::test::beside;
using canhil::test::OwnBus;
using canhil::test::shell;

struct Logged {
  long long stamp_us = 0;  // candump's microseconds, whole (a double loses them past 1e9 s)
  frames::WireFrame frame;
};

// candump -L lines: "(1700000000.123456) vcan0 123#0011223344556677".
std::vector<Logged> read_log(const std::string& text) {
  std::vector<Logged> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    Logged l;
    char iface[32];
    char body[160];
    long long seconds = 0;
    long long micros = 0;
    if (std::sscanf(line.c_str(), "(%lld.%lld) %31s %159s", &seconds, &micros, iface, body) != 4) continue;
    l.stamp_us = seconds * 1'000'000 + micros;
    const std::string b = body;
    const auto hash = b.find('#');
    if (hash == std::string::npos) continue;
    l.frame.id = static_cast<std::uint32_t>(std::stoul(b.substr(0, hash), nullptr, 16));
    l.frame.extended = hash > 3;
    const std::string data = b.substr(hash + 1);
    l.frame.len = static_cast<std::uint8_t>(data.size() / 2);
    for (std::size_t k = 0; k < l.frame.len; ++k)
      l.frame.data[k] = static_cast<std::uint8_t>(std::stoul(data.substr(2 * k, 2), nullptr, 16));
    out.push_back(l);
  }
  return out;
}

class TimedBus : public OwnBus {
 protected:
  void timed(std::uint32_t bit_rate) {
    start({"vcan0"});
    ub::LinkSettings link;
    link.bit_rate = bit_rate;
    ub::set_link(paths_, "vcan0", link);
  }
};

TEST_F(TimedBus, CangenAsFastAsItCanGoesAtTheWiresRateAndMeetsENOBUFS) {
  timed(1'000'000);
  // cangen -g 0 writes without pause; -i counts the writes a full queue refused.
  const std::string out = on_bus(
      beside("candump -L vcan0 > log.txt", "cangen -g 0 -i -n 100000 -L 8 -D r vcan0; sleep 0.2", true, "cat log.txt"));
  const std::vector<Logged> log = read_log(out);
  ASSERT_GT(log.size(), 10U) << out.substr(0, 400);
  EXPECT_NE(out.find("ENOBUFS return values"), std::string::npos)
      << "a 10-frame queue overflows: " << out.substr(0, 400);
  std::size_t back_to_back = 0;
  for (std::size_t k = 1; k < log.size(); ++k) {
    // Never faster than the wire: a frame ends at least its own bits after the one before.
    const long long bits_us = frames::count_bits(log[k].frame).total();
    const long long gap_us = log[k].stamp_us - log[k - 1].stamp_us;
    EXPECT_GE(gap_us, bits_us - 1) << "frame " << k << " of " << log.size();  // candump's stamps: whole us
    if (gap_us - bits_us <= 1) ++back_to_back;
  }
  EXPECT_GT(back_to_back, 0U) << "with a full queue, frames follow each other at the wire's rate";
}

TEST_F(TimedBus, ErrorFramesReachCandumpAndPythonCanAsCanDevDriversGiveThem) {
  timed(1'000'000);
  // python-can and plain sockets: the echo at the end of frame with
  // MSG_CONFIRM, ENOBUFS, and error frames (a missing acknowledgement).
  int status = -1;
  const std::string py =
      on_bus(beside("candump vcan0 > /dev/null",
                    "/usr/bin/python3 " + canhil::test::source_dir() + "/tests/userbus/python_wire_check.py " +
                        canhil::test::canhil_binary() + "; echo python $?",
                    true),
             &status);
  EXPECT_NE(py.find("echo: MSG_CONFIRM True, MSG_DONTROUTE True"), std::string::npos) << py;
  EXPECT_NE(py.find("python-can: 3 error frames, the first 0x2A8"), std::string::npos) << py;
  EXPECT_NE(py.find("heard 3 of 3 frames"), std::string::npos) << py;
  EXPECT_NE(py.find("python 0"), std::string::npos) << py;
  // candump -e: every frame corrupted for a while, each receiver's error frames.
  const std::string dumped = on_bus(beside(
      "candump -e vcan0,0:0,#FFFFFFFF > e.txt",
      canhil::test::canhil_binary() + " bus fault vcan0 error:*:1; cangen -g 2 -i -n 20 -L 8 -D i vcan0; sleep 0.1; " +
          canhil::test::canhil_binary() + " bus fault vcan0 clear",
      true, "cat e.txt"));
  EXPECT_NE(dumped.find("ERRORFRAME"), std::string::npos) << dumped.substr(0, 600);
  EXPECT_NE(dumped.find("20000288   [8]"), std::string::npos)
      << "PROT|BUSERROR|CNT, as can-dev: " << dumped.substr(0, 600);
  const std::string listed = ub::describe(paths_);
  EXPECT_NE(listed.find("bitrate 1000000"), std::string::npos) << listed;
  EXPECT_EQ(listed.find("error frames 0\n"), std::string::npos) << listed;
}

TEST_F(TimedBus, AControllerForcedBusOffSendsNothingUntilRestartedOnRequest) {
  timed(500'000);
  const std::string canhil = canhil::test::canhil_binary();
  ASSERT_EQ(shell("CANHIL_BUS_DIR='" + folder_.string() + "' " + canhil + " bus link vcan0 restart-ms 0"), "");
  // cangen sends every 5 ms until killed (however long the commands take: a
  // loaded machine, a sanitizer); bus-off at once; the count candump sees
  // holds still; a restart lets it go on.
  const std::string out = on_bus(
      beside("candump vcan0 > d.txt",
             "cangen -g 5 -i -I 123 -L 2 vcan0 & g=$!; sleep 0.3; " + canhil + " bus fault vcan0 busoff:cangen; " +
                 "sleep 0.05; " + canhil +
                 " bus list | grep cangen; a=$(wc -l < d.txt); sleep 0.3; b=$(wc -l < d.txt); " + "echo held $a $b; " +
                 canhil + " bus link vcan0 restart; sleep 0.3; " + canhil + " bus list | grep cangen; kill $g",
             true, "wc -l < d.txt"));
  EXPECT_NE(out.find("(cangen)  vcan0  bus-off  tec 256"), std::string::npos) << out;
  const auto held = out.find("held ");
  ASSERT_NE(held, std::string::npos) << out;
  int a = -1;
  int b = -2;
  std::sscanf(out.c_str() + held, "held %d %d", &a, &b);
  EXPECT_EQ(a, b) << "nothing from a bus-off controller: " << out;
  EXPECT_NE(out.find("error-active  tec 0 rec 0"), std::string::npos) << out;
  EXPECT_NE(out.find("bus-off 1  restarts 1"), std::string::npos) << out;
}

TEST_F(TimedBus, LinkSettingsAreCheckedAndSaidAsIpLinkSaysThem) {
  start({"vcan0"});
  const std::string canhil = "CANHIL_BUS_DIR='" + folder_.string() + "' " + canhil::test::canhil_binary();
  int status = -1;
  const std::string set = shell(canhil + " bus link vcan0 bitrate 250000 restart-ms 50 txqueuelen 32", &status);
  EXPECT_EQ(status, 0) << set;
  EXPECT_NE(ub::describe(paths_).find("bitrate 250000  restart-ms 50  txqueuelen 32  load 0.0 %"), std::string::npos)
      << ub::describe(paths_);
  EXPECT_NE(shell(canhil + " bus link vcan0 bitrate fast", &status).find("bitrate takes a whole number, got \"fast\""),
            std::string::npos);
  EXPECT_NE(status, 0);
  EXPECT_NE(shell(canhil + " bus link vcan0 bitrate 10").find("bitrate takes 1000 to 20000000 bit/s"),
            std::string::npos);
  EXPECT_NE(shell(canhil + " bus link vcan0 speed 9").find("no link setting \"speed\""), std::string::npos);
  EXPECT_NE(shell(canhil + " bus link vcan0 restart").find("no controller on vcan0 is bus-off"), std::string::npos);
  EXPECT_NE(shell(canhil + " bus fault vcan0 busoff:nobody").find("a program on vcan0"), std::string::npos);
  EXPECT_NE(shell(canhil + " bus fault vcan0 drop:*").find("a running bus takes ber, error"), std::string::npos);
  ASSERT_EQ(shell(canhil + " bus link vcan0 bitrate 0", &status), "");
  EXPECT_NE(ub::describe(paths_).find("instant (no wire)"), std::string::npos);
  EXPECT_NE(shell(canhil + " bus link vcan0 restart").find("vcan0 has no wire"), std::string::npos);
}

}  // namespace
