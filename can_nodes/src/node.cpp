#include "canhil/can_nodes/node.hpp"

#include <algorithm>

namespace canhil::can_nodes {

Node::Node(std::string name, Endpoint& bus, std::shared_ptr<const frames::MessageSet> set)
    : bus_(bus),
      tm_length_(static_cast<std::uint8_t>(set->tm.message().def().length)),
      tm_(&set->tm.message()),
      set_(std::move(set)),
      name_(std::move(name)) {
  wakes_.reserve(kWakesInside);  // in wake_space_: more grow into the heap
}

std::size_t Node::poll() { return poll(~std::size_t{0}); }

std::size_t Node::poll(std::size_t max_frames) {
  std::size_t n = 0;
  while (n < max_frames) {
    auto f = bus_.receive();
    if (!f) break;
    ++n;
    if (!enabled_) continue;  // switched off: hears nothing
    ++counters_.received;
    const frames::CanFrame& frame = f->frame;
    if (frames::is_message(frame, *tm_) && frame.len == tm_length_) {
      ++counters_.triggers;
    }
    on_frame(*f);
  }
  return n + poll_more(max_frames);
}

void Node::note_next() noexcept {
  next_ = wakes_.empty() ? kNever : wakes_.front();
  if (!delayed_.empty()) next_ = std::min(next_, delayed_.front().first);
}

void Node::wake_at(Nanos t) {
  if (t < next_) next_ = t;
  const auto at = std::lower_bound(wakes_.begin(), wakes_.end(), t);
  if (at == wakes_.end() || *at != t) wakes_.insert(at, t);
}

void Node::tick(Nanos now) {
  if (next_ > now) return;  // neither a delayed frame nor a wake-up is due
  while (!delayed_.empty() && delayed_.front().first <= now) {
    const frames::CanFrame f = delayed_.front().second;
    delayed_.erase(delayed_.begin());
    if (enabled_) send_now(f);
  }
  if (!wakes_.empty() && wakes_.front() <= now) {
    // Serve every request that is due with one step; step() may add more.
    wakes_.erase(wakes_.begin(), std::upper_bound(wakes_.begin(), wakes_.end(), now));
    note_next();
    step(now);
  }
  note_next();
}

void Node::emit(const frames::CanFrame& frame, Nanos now) {
  if (!enabled_) return;
  FaultDecision d;
  if (hook_ != nullptr) d = hook_->on_send(name_, frame, now);
  if (d.drop) {
    ++counters_.fault_dropped;
    return;
  }
  if (d.error_frame) {
    ++counters_.error_frames;  // not a frame the node sent: no `sent` count
    if (bus_.send(frames::make_bus_error_frame()) != SendStatus::kOk) ++counters_.send_failed;
  }
  frames::CanFrame f = frame;
  if (d.corrupt_byte >= 0 && d.corrupt_byte < 8) {
    f.data[static_cast<std::size_t>(d.corrupt_byte)] ^= d.corrupt_mask;
  }
  for (int copy = 0; copy <= d.duplicates; ++copy) {
    if (d.delay > Nanos{0}) {
      const Nanos due = now + d.delay;
      const auto at =
          std::upper_bound(delayed_.begin(), delayed_.end(), due, [](Nanos t, const auto& e) { return t < e.first; });
      delayed_.insert(at, {due, f});
      note_next();
    } else {
      send_now(f);
    }
  }
}

void Node::send_now(frames::CanFrame frame) {
  if (bus_.send(frame) == SendStatus::kOk) {
    ++counters_.sent;
  } else {
    ++counters_.send_failed;
  }
}

}  // namespace canhil::can_nodes
