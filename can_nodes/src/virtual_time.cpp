#include "canhil/can_nodes/virtual_time.hpp"

#include <algorithm>

namespace canhil::can_nodes {

void WakeTree::push_back(Nanos w) {
  if (size_ == leaves_) {
    const std::size_t leaves = leaves_ == 0 ? 8 : 2 * leaves_;
    std::vector<std::int64_t> grown(2 * leaves, kNever.count());
    std::copy_n(node_.begin() + static_cast<std::ptrdiff_t>(leaves_), size_,
                grown.begin() + static_cast<std::ptrdiff_t>(leaves));
    for (std::size_t n = leaves - 1; n >= 1; --n) grown[n] = std::min(grown[2 * n], grown[2 * n + 1]);
    node_ = std::move(grown);
    leaves_ = leaves;
  }
  set(size_++, w);
}

void WakeTree::set(std::size_t i, Nanos w) noexcept {
  std::size_t n = leaves_ + i;
  node_[n] = w.count();
  for (n /= 2; n >= 1; n /= 2) {
    const std::int64_t least = std::min(node_[2 * n], node_[2 * n + 1]);
    if (node_[n] == least) break;  // nothing above changes
    node_[n] = least;
  }
}

void WakeTree::due(Nanos now, std::vector<std::size_t>& out) const {
  if (earliest() > now) return;
  // Every leaf due now, the earlier index first, without a stack: down into
  // a due subtree (a node is due only when one of its children is), the left
  // child first; from a leaf, up until a left child whose right sibling is due.
  const std::int64_t t = now.count();
  std::size_t node = 1;
  while (true) {
    while (node < leaves_) node = node_[2 * node] <= t ? 2 * node : 2 * node + 1;
    out.push_back(node - leaves_);
    while (node % 2 == 1 || node_[node + 1] > t) {
      if (node == 1) return;
      node /= 2;
    }
    ++node;
  }
}

void Participants::add(Participant& p) {
  const std::size_t i = list_.size();
  list_.push_back(&p);
  bell_->resize(list_.size());
  rings_.push_back(p.set_doorbell(bell_, i) ? 1 : 0);
  if (rings_[i] == 0 || p.may_have_frames()) bell_->ring(i);  // those that cannot ring stay rung
  kept_.push_back(p.wakeup_is_own() ? 1 : 0);
  wake_.push_back(kNever);
  keep(i);
  if (kept_[i] == 0) asked_.push_back(i);
}

void Participants::add(Node& node) {
  owned_.emplace_back(node);
  add(owned_.back());
}

std::size_t Participants::poll(std::size_t i) {
  Participant* p = list_[i];
  if (rings_[i] != 0) {
    bell_->clear(i);  // frames arriving while it polls ring it again
  } else if (!p->may_have_frames()) {
    return 0;
  }
  const std::size_t n = p->poll();
  keep(i);
  return n;
}

void Participants::deliver() {
  for (int round = 0; round < 10'000; ++round) {
    std::size_t handled = 0;
    for (std::size_t i = bell_->next(0); i != Doorbell::kNone; i = bell_->next(i + 1)) handled += poll(i);
    if (handled == 0) return;
  }
}

void Participants::deliver_some(std::size_t budget) {
  for (std::size_t i = 0; i < list_.size(); ++i) {
    list_[i]->poll_some(budget);
    if (rings_[i] != 0 && !list_[i]->may_have_frames()) bell_->clear(i);
    keep(i);
  }
}

void Participants::tick_due(const Clock& clock, std::size_t budget) {
  for (int round = 0; round < 64; ++round) {
    const Nanos now = clock.now();
    bool any = false;
    // The kept ones due (only its own tick moves one's wake-up), found in
    // the tree of kept wake-ups, merged in order with the asked ones, each
    // asked in its turn.
    due_.clear();
    wake_.due(now, due_);
    std::size_t k = 0, a = 0;
    while (k < due_.size() || a < asked_.size()) {
      const bool asked = k == due_.size() || (a < asked_.size() && asked_[a] < due_[k]);
      const std::size_t i = asked ? asked_[a++] : due_[k++];
      if (asked && list_[i]->next_wakeup() > now) continue;
      list_[i]->tick(now);
      keep(i);
      any = true;
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
  Nanos t = wake_.earliest();
  for (const std::size_t i : asked_) t = std::min(t, list_[i]->next_wakeup());
  return t;
}

void Participants::refresh() {
  for (std::size_t i = 0; i < list_.size(); ++i) keep(i);
}

void VirtualTime::set_step(Nanos period, std::function<void(Nanos now)> step) {
  step_ = std::move(step);
  steps_at_ = Periodic(period, clock_.now() + period);
}

void VirtualTime::run_until(Nanos end) {
  participants_.refresh();  // the caller may have moved wake-ups between runs
  while (true) {
    const Nanos next = std::min(steps_at_.next(), participants_.next_wakeup());
    if (next > end) break;
    clock_.set(std::max(next, clock_.now()));
    const Nanos now = clock_.now();
    if (steps_at_.due(now)) {
      steps_at_.advance();
      ++steps_;
      step_(now);
      participants_.refresh();  // the step may move wake-ups (a vision frame wakes an agent)
    }
    participants_.deliver();
    participants_.tick_due(clock_);
  }
  if (clock_.now() < end) clock_.set(end);
  participants_.deliver();
}

}  // namespace canhil::can_nodes
