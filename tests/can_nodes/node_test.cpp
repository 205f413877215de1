// What every node has in common: wake-ups served in order however many are
// asked for (a few live in the node, more spill over), each instant's
// requests served by one step, and the next wake-up kept as they change.
#include "canhil/can_nodes/node.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "canhil/can_nodes/memory_bus.hpp"
#include "support/test_paths.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

// Asks for the wake-ups it is given and notes when it steps; a step may ask for more.
class Waker final : public Node {
 public:
  Waker(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set) : Node("waker", bus, std::move(set)) {}
  void ask(Nanos t) { wake_at(t); }
  std::vector<Nanos> steps;
  std::vector<Nanos> then;  // asked for by the first step

 protected:
  void on_frame(const frames::TimedFrame&) override {}
  void step(Nanos now) override {
    steps.push_back(now);
    for (const Nanos t : then) wake_at(t);
    then.clear();
  }
};

TEST(Node, WakeUpsAreServedInOrderOncePerInstantHoweverManyAreAsked) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  auto ep = bus.attach("waker");
  Waker node(*ep, frames::MessageSet::load(test::shipped_dbc()));
  EXPECT_EQ(node.next_wakeup(), kNever);
  std::mt19937 pick(4);
  std::vector<Nanos> asked;
  for (int i = 0; i < 40; ++i) {  // more than live in the node, in random order, some twice
    const Nanos t = std::chrono::milliseconds(1 + pick() % 30);
    node.ask(t);
    asked.push_back(t);
  }
  std::sort(asked.begin(), asked.end());
  asked.erase(std::unique(asked.begin(), asked.end()), asked.end());
  EXPECT_EQ(node.next_wakeup(), asked.front());
  node.then = {2500us, 45ms};  // the first step asks for one between the others and one after them all
  std::vector<Nanos> want = asked;
  for (const Nanos t : node.then) want.push_back(t);
  std::sort(want.begin(), want.end());
  node.tick(0ms);  // nothing due
  EXPECT_TRUE(node.steps.empty());
  while (node.next_wakeup() != kNever) {
    const Nanos t = node.next_wakeup();
    node.tick(t);
    ASSERT_FALSE(node.steps.empty());
    ASSERT_EQ(node.steps.back(), t);
  }
  EXPECT_EQ(node.steps, want);
}

}  // namespace
}  // namespace canhil::can_nodes
