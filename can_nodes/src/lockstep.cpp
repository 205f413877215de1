#include "canhil/can_nodes/lockstep.hpp"

#include <algorithm>

namespace canhil::can_nodes {

void Participants::add(Node& node) {
  owned_.push_back(std::make_unique<NodeParticipant>(node));
  list_.push_back(owned_.back().get());
}

void Participants::deliver() {
  for (int round = 0; round < 10'000; ++round) {
    std::size_t handled = 0;
    for (Participant* p : list_) {
      if (p->may_have_frames()) handled += p->poll();
    }
    if (handled == 0) return;
  }
}

void Participants::deliver_some(std::size_t budget) {
  for (Participant* p : list_) p->poll_some(budget);
}

void Participants::tick_due(const Clock& clock, std::size_t budget) {
  for (int round = 0; round < 64; ++round) {
    const Nanos now = clock.now();
    bool any = false;
    for (Participant* p : list_) {
      if (p->next_wakeup() <= now) {
        p->tick(now);
        any = true;
      }
    }
    if (budget == kUnlimited) {
      deliver();
    } else {
      deliver_some(budget);
    }
    if (!any) return;
  }
}

Nanos Participants::next_wakeup() const {
  Nanos t = kNever;
  for (const Participant* p : list_) t = std::min(t, p->next_wakeup());
  return t;
}

void Lockstep::set_step(Nanos period, std::function<void(Nanos now)> step) {
  period_ = period;
  step_ = std::move(step);
  next_step_ = clock_.now() + period_;
}

void Lockstep::run_until(Nanos end) {
  while (true) {
    const Nanos next = std::min(next_step_, participants_.next_wakeup());
    if (next > end) break;
    clock_.set(std::max(next, clock_.now()));
    const Nanos now = clock_.now();
    if (next_step_ <= now) {
      next_step_ += period_;
      ++steps_;
      step_(now);
    }
    participants_.deliver();
    participants_.tick_due(clock_);
  }
  if (clock_.now() < end) clock_.set(end);
  participants_.deliver();
}

}  // namespace canhil::can_nodes
