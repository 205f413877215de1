#include "canhil/emulator/lockstep.hpp"

#include <algorithm>

namespace canhil::emulator {

Lockstep::Lockstep(can_nodes::SimulatedClock& clock, physics::World* world) : clock_(clock), world_(world) {
  if (world_ != nullptr) {
    step_ = std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(world_->params().simulation.step_s));
    next_step_ = clock_.now() + step_;
  }
}

void Lockstep::add(can_nodes::Node& node) {
  owned_.push_back(std::make_unique<NodeParticipant>(node));
  participants_.push_back(owned_.back().get());
}

void Lockstep::deliver() {
  // Frames sent while handling frames are delivered in the same instant.
  while (true) {
    std::size_t handled = 0;
    for (Participant* p : participants_) handled += p->poll();
    if (handled == 0) return;
  }
}

void Lockstep::run_until(Nanos end) {
  while (true) {
    Nanos next = world_ != nullptr ? next_step_ : can_nodes::kNever;
    for (const Participant* p : participants_) next = std::min(next, p->next_wakeup());
    if (next > end) break;
    clock_.set(std::max(next, clock_.now()));
    const Nanos now = clock_.now();
    if (world_ != nullptr && next_step_ <= now) {
      world_->step();
      ++steps_;
      next_step_ += step_;
      if (after_step_) after_step_(now);
    }
    deliver();
    // Everyone due now, repeatedly: a participant may ask to be woken again now.
    for (int round = 0; round < 64; ++round) {
      bool any = false;
      for (Participant* p : participants_) {
        if (p->next_wakeup() <= now) {
          p->tick(now);
          any = true;
        }
      }
      deliver();
      if (!any) break;
    }
  }
  if (clock_.now() < end) clock_.set(end);
  deliver();
}

}  // namespace canhil::emulator
