// tests/support/counter_watch.hpp — a test fixture that fails the test when
// an error counter moved that the test did not expect (after MuJoCo's test
// fixture, which fails on any engine warning). A test registers what it runs
// (a robot's nodes, a handler's statistics, any counter by name), runs, and
// declares what it meant to provoke with expect() or allow(); TearDown fails
// the test for every other counter that moved, naming it and by how much.
// Silent trouble (a dropped frame, an unknown id, a missed TM) cannot pass
// unnoticed behind assertions about something else.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "canhil/can_nodes/robot_nodes.hpp"

namespace canhil::test {

class CounterWatch {
 public:
  using Getter = std::function<std::uint64_t()>;

  /// Watches one counter from its value now; names must be unique.
  void watch(const std::string& name, Getter get) {
    const std::uint64_t start = get();
    counters_[name] = Counter{std::move(get), start, std::nullopt, false};
  }
  /// Every error counter of a robot's emulated nodes (bad frames by kind, send
  /// failures, fault drops, error frames) and of their bus endpoints
  /// (receive overflow, send drops), as `prefix`NODE.COUNTER.
  void watch_nodes(const can_nodes::RobotNodes& nodes, const std::string& prefix = "") {
    for (std::size_t i = 0; i < can_nodes::kNodeCount; ++i) {
      if (!nodes.emulates(static_cast<can_nodes::NodeId>(i))) continue;  // a real board's
      const can_nodes::Node& n = nodes.node(static_cast<can_nodes::NodeId>(i));
      const std::string p = prefix + n.name() + ".";
      watch(p + "wrong_length", [&n] { return n.counters().wrong_length; });
      watch(p + "out_of_range", [&n] { return n.counters().out_of_range; });
      watch(p + "unknown_id", [&n] { return n.counters().unknown_id; });
      watch(p + "send_failed", [&n] { return n.counters().send_failed; });
      watch(p + "fault_dropped", [&n] { return n.counters().fault_dropped; });
      watch(p + "error_frames", [&n] { return n.counters().error_frames; });
      watch(p + "rx_overflow", [&n] { return n.bus().stats().rx_overflow; });
      watch(p + "send_dropped", [&n] { return n.bus().stats().send_dropped; });
    }
  }
  /// Every robot's node counters of a session whose driver has built its
  /// nodes, as INTERFACE.NODE.COUNTER, until the returned guard goes (declare
  /// it after the driver: it checks and forgets them while the nodes still
  /// exist, however the test ends). A template, so that node tests need not
  /// link the emulator.
  template <class Session>
  [[nodiscard]] auto watch_session(const Session& session) {
    for (std::size_t r = 0; r < session.robot_count(); ++r) {
      const auto& rig = session.rig(r);
      if (rig.nodes) watch_nodes(*rig.nodes, rig.interface + ".");
    }
    struct Guard {
      explicit Guard(CounterWatch* w) : watch(w) {}
      CounterWatch* watch;
      Guard(const Guard&) = delete;
      Guard& operator=(const Guard&) = delete;
      ~Guard() { watch->finish(); }
    };
    return Guard(this);
  }
  /// The test provokes exactly `n` on this counter (by the end).
  void expect(const std::string& name, std::uint64_t n) { find(name).expected = n; }
  /// The test provokes some on this counter; any amount is fine.
  void allow(const std::string& name) { find(name).allowed = true; }
  /// Every counter whose name starts with `prefix` may move.
  void allow_prefix(const std::string& prefix) {
    for (auto& [name, c] : counters_) {
      if (name.rfind(prefix, 0) == 0) c.allowed = true;
    }
  }
  /// Every counter whose name ends with `suffix` may move (".rx_overflow":
  /// every node's, where a busy machine may fill a queue).
  void allow_suffix(const std::string& suffix) {
    for (auto& [name, c] : counters_) {
      if (name.size() >= suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
        c.allowed = true;
      }
    }
  }
  /// How much a counter moved so far.
  std::uint64_t moved(const std::string& name) { return find(name).get() - find(name).start; }

  /// Checks now and forgets every counter: for a test whose watched objects
  /// are its own locals (they must not be read after they are gone).
  void finish() {
    check();
    counters_.clear();
  }

  /// Fails the running test for each counter that moved unexpectedly (or
  /// not by its expected amount). The watched objects must still exist.
  void check() const {
    for (const auto& [name, c] : counters_) {
      const std::uint64_t d = c.get() - c.start;
      if (c.expected) {
        EXPECT_EQ(d, *c.expected) << name << " moved by " << d << ", the test expected " << *c.expected;
      } else if (!c.allowed && d != 0) {
        ADD_FAILURE() << name << " moved by " << d << " and the test did not expect it";
      }
    }
  }

 private:
  struct Counter {
    Getter get;
    std::uint64_t start = 0;
    std::optional<std::uint64_t> expected;
    bool allowed = false;
  };
  Counter& find(const std::string& name) {
    const auto it = counters_.find(name);
    if (it == counters_.end()) {
      ADD_FAILURE() << "no counter " << name << " is watched";
      static Counter none{[] { return std::uint64_t{0}; }, 0, std::nullopt, true};
      return none;
    }
    return it->second;
  }
  std::map<std::string, Counter> counters_;
};

/// A fixture whose TearDown checks the counters its test registered.
class WatchedTest : public ::testing::Test {
 protected:
  void TearDown() override { counters.check(); }
  CounterWatch counters;
};

}  // namespace canhil::test
