#include "canhil/can_nodes/realtime.hpp"

#include <algorithm>

namespace canhil::can_nodes {
namespace {

// Frames one node handles per pass of the loop: enough for any burst of the
// message set (a few dozen frames an EC), small enough that a socket flooded
// with other traffic costs a pass well under a millisecond.
constexpr std::size_t kPollBudget = 64;

}  // namespace

void Realtime::run_until(Nanos end, const std::atomic<bool>& stop) {
  participants_.refresh();  // the owner may have moved wake-ups since they were added
  while (!stop.load(std::memory_order_relaxed)) {
    wait_(std::min(end, participants_.next_wakeup()));
    ++wakeups_;
    if (on_pass_) {
      on_pass_();
      participants_.refresh();  // its changes may move wake-ups
    }
    // Timers first: a frame due goes out before the sockets are read (each
    // read is a system call, and a flooded socket has many). Bounded reads:
    // under a flood the loop comes straight back (the socket stays readable).
    participants_.tick_due(clock_, kPollBudget);
    participants_.deliver_some(kPollBudget);
    participants_.tick_due(clock_, kPollBudget);
    if (clock_.now() >= end) break;
  }
}

}  // namespace canhil::can_nodes
