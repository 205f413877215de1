// What a driver's bus watch makes of the frames it is shown: counts per bus,
// one candump trace in time order (then robot, then arrival), a trace left
// empty when not asked for, and the load and frame counts a watcher reads.
#include "canhil/emulator/bus_watch.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include "canhil/frames/messages.hpp"
#include "support/counter_watch.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

using namespace std::chrono_literals;

class BusWatchTest : public test::WatchedTest {
 protected:
  BusWatchTest() {
    setenv("RTDB_KEY", std::to_string(0x5C000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    scenario_.world.robots = {physics::Placement{-3.0, 0.0, 0}, physics::Placement{3.0, 0.0, 0}};
    options_.messages = frames::MessageSet::load(test::shipped_dbc());
    options_.vision_on = false;
  }
  static frames::TimedFrame frame(std::uint32_t id, Nanos at) {
    frames::TimedFrame f;
    f.frame.id = id;
    f.frame.len = 1;
    f.time = at;
    return f;
  }
  Scenario scenario_;
  SessionOptions options_;
};

TEST_F(BusWatchTest, OneTraceByTimeThenRobotThenArrival) {
  const Session session(plan_run(scenario_, options_));
  BusWatch watch(session, {});
  watch.add(1, frame(0x10, Nanos{1ms}));
  watch.add(0, frame(0x20, Nanos{2ms}));
  watch.add(0, frame(0x21, Nanos{1ms}));  // late on its bus: the trace still puts it by time
  watch.add(1, frame(0x11, Nanos{1ms}));
  EXPECT_EQ(watch.frames(0), 2u);
  EXPECT_EQ(watch.frames(1), 2u);
  const std::string t = watch.trace();
  const std::string a = session.rig(0).interface, b = session.rig(1).interface;
  const auto at = [&](const std::string& what) { return t.find(what); };
  ASSERT_NE(at(a + " 021#"), std::string::npos) << t;
  EXPECT_LT(at(a + " 021#"), at(b + " 010#")) << "at 1 ms robot 0 first";
  EXPECT_LT(at(b + " 010#"), at(b + " 011#")) << "then in arrival order";
  EXPECT_LT(at(b + " 011#"), at(a + " 020#")) << "2 ms last";
  EXPECT_EQ(watch.ftt_violations(0), 0u) << "no checker asked for";
}

TEST_F(BusWatchTest, NoTraceUnlessAskedAndTheMeasuresForAWatcher) {
  const Session session(plan_run(scenario_, options_));
  BusWatch watch(session, {.record_trace = false, .check_timing = false});
  for (int k = 0; k < 100; ++k) watch.add(0, frame(0x10, Nanos{std::chrono::milliseconds(k)}));
  EXPECT_EQ(watch.trace(), "");
  std::vector<BusDetail> buses;
  watch.fill(buses, Nanos{1s});
  ASSERT_EQ(buses.size(), 2u);
  EXPECT_EQ(buses[0].frames, 100u);
  EXPECT_EQ(buses[0].load, 0.0) << "measured from the first fill on";
  for (int k = 0; k < 1000; ++k) watch.add(0, frame(0x10, Nanos{1s} + Nanos{std::chrono::milliseconds(k)}));
  watch.fill(buses, Nanos{2s});
  EXPECT_GT(buses[0].load, 0.0);
  EXPECT_EQ(buses[1].load, 0.0);
  EXPECT_EQ(buses[0].frames, 1100u);
}

}  // namespace
}  // namespace canhil::emulator
