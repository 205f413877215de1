#include "canhil/wire/wire_bus.hpp"

#include <algorithm>

#include "bit_counts.hpp"
#include "canhil/base/demand.hpp"
#include "canhil/wire/error_frames.hpp"

namespace canhil::wire {
using namespace bit_counts;  // NOLINT(google-build-using-namespace): the model's own constants

WireBus::WireBus(const WireConfig& config) : config_(config), faults_(config.seed) {
  CANHIL_DEMAND(config.bit_rate > 0, "a timed wire needs a bit rate");
  const auto whole = [](std::uint32_t rate) -> std::int64_t {
    return 1'000'000'000 % rate == 0 ? 1'000'000'000 / rate : 0;
  };
  bit_ns_ = whole(config.bit_rate);
  fast_bit_ns_ = whole(config.data_bit_rate != 0 ? config.data_bit_rate : config.bit_rate);
}

ControllerId WireBus::add_controller(std::string name, const ControllerOptions& options) {
  Controller c;
  c.name = std::move(name);
  c.options = options;
  c.counts.name = c.name;
  c.calm_frames = stats_.frames;
  controllers_.push_back(std::move(c));
  fronts_.emplace_back();
  ++present_;
  if (calm_) choose_again(now_ + Nanos{1});  // one more to acknowledge a frame not started
  return static_cast<ControllerId>(controllers_.size() - 1);
}

void WireBus::remove_controller(ControllerId controller) {
  Controller& k = controllers_.at(controller);
  if (k.gone) return;
  k.counts.received += calm_received(k);
  k.gone = true;
  --present_;
  if (wire_ && wire_->from == controller) {
    if (calm_ && wire_->start > now_) {
      wire_.reset();  // chosen, not started: gone with its queue
    } else if (!wire_->babble) {
      babble_ = k.queue.front();  // its frame finishes; nothing left to pop
      wire_->babble = true;
    }
  }
  k.queue.clear();
  queue_changed(controller);
  k.restart_at = kNever;
  k.recovering = false;
  if (calm_) choose_again(now_ + Nanos{1});  // one fewer to acknowledge a frame not started
  next_stale_ = true;
}

Nanos WireBus::frame_time(const frames::WireFrame& f, std::uint32_t bit_count) const noexcept {
  return frame_bits(frames::prefix_bits(f, bit_count));
}

WireBus::Queued* WireBus::slot(Controller& k) {
  if (k.queue.size() >= k.options.queue_frames) {
    ++k.counts.refused;
    return nullptr;
  }
  return &k.queue.push_slot();  // every field set before it is read
}

WireBus::Submit WireBus::submit(ControllerId controller, const frames::WireFrame& frame, Nanos now, std::uint64_t tag) {
  Queued* q = slot(controllers_.at(controller));
  if (q == nullptr) return Submit::kQueueFull;
  q->frame = frame;
  return given(controller, *q, now, tag);
}

WireBus::Submit WireBus::submit(ControllerId controller, const frames::CanFrame& frame, Nanos now, std::uint64_t tag) {
  Queued* q = slot(controllers_.at(controller));
  if (q == nullptr) return Submit::kQueueFull;
  // In place: the slot's bytes past a classic frame's 8 are never read (WireEvent, count_bits).
  frames::wire_frame_into(frame, q->frame);
  return given(controller, *q, now, tag);
}

WireBus::Submit WireBus::given(ControllerId controller, Queued& q, Nanos now, std::uint64_t tag) {
  Controller& k = controllers_[controller];
  const frames::WireFrame& frame = q.frame;
  q.key = frames::arbitration_key(frame.id, frame.extended, frame.remote && !frame.fd);
  q.seq = seq_++;
  q.tag = tag;
  q.given = now;
  q.bits = frames::count_bits(frame);
  queue_changed(controller);
  if (calm_) {
    // Only a frame at its queue's head, ready by the chosen frame's start,
    // and before it in arbitration, changes the choice.
    const bool may_win = wire_ && wire_->start >= now && k.queue.size() == 1;
    const Nanos ready = may_win ? ready_at(controller) : kNever;
    if (!wire_ || ready < wire_->start || (ready == wire_->start && q.key < wire_->key)) choose_again(now);
    next_stale_ = true;
    return Submit::kQueued;
  }
  if (now == now_ && k.queue.size() == 1 && ready_at(controller) == now) {
    if (wire_ && wire_->start == now && !wire_->babble && q.key < wire_->key) {
      // Arbitration began at this very instant: the frame given now takes part, and wins.
      wire_.reset();
    }
    if (!wire_) arbitrate(now);
  }
  next_stale_ = true;
  return k.confinement.bus_off() ? Submit::kBusOff : Submit::kQueued;
}

std::size_t WireBus::queued() const noexcept {
  std::size_t n = 0;
  for (const Controller& k : controllers_) n += k.queue.size();
  return n;
}

void WireBus::choose_again(Nanos now) {
  if (wire_ && wire_->start >= now) wire_.reset();  // not started (or starting now: a frame given now takes part)
  next_stale_ = true;
  if (wire_) return;
  // In one pass: the earliest instant a frame can start, and the first in
  // arbitration among those ready then (lowest key; equal keys, the one given first).
  Nanos at = kNever;
  ControllerId from = 0;
  std::uint64_t key = 0, seq = 0;
  const auto consider = [&](ControllerId c) {
    const Nanos ready = calm_ready(c);
    const Front& head = fronts_[c];
    if (ready > at || (ready == at && (head.key > key || (head.key == key && head.seq > seq)))) return;
    at = ready;
    from = c;
    key = head.key;
    seq = head.seq;
  };
  // Calm (only a calm bus chooses early): those waiting, from their fronts
  // alone; the mask says whose queues have frames, where it can.
  if (controllers_.size() <= 64) {
    for (std::uint64_t w = waiting_; w != 0; w &= w - 1) consider(static_cast<ControllerId>(std::countr_zero(w)));
  } else {
    for (ControllerId c = 0; c < controllers_.size(); ++c) {
      if (!controllers_[c].queue.empty()) consider(c);
    }
  }
  if (at != kNever) put_on_wire(from, key, nullptr, at);
}

void WireBus::end_calm() noexcept {
  if (!calm_) return;
  for (Controller& k : controllers_) k.counts.received += calm_received(k);
  calm_ = false;
}

void WireBus::begin_calm() noexcept {
  for (Controller& k : controllers_) {
    k.calm_frames = stats_.frames;
    k.calm_sent = k.sent;
  }
  calm_ = true;
}

bool WireBus::acknowledged(ControllerId from) const noexcept {
  // Calm: nobody bus-off, nobody cut off; everyone else present acknowledges.
  if (calm_) return present_ > (controllers_[from].gone ? 0 : 1);
  for (ControllerId c = 0; c < controllers_.size(); ++c) {
    if (c != from && !controllers_[c].confinement.bus_off() && !off_bus(c, now_)) return true;
  }
  return false;
}

Nanos WireBus::ready_at_with_rules(ControllerId c) const noexcept {
  const Controller& k = controllers_[c];
  if (k.confinement.bus_off()) return kNever;
  const Nanos earliest = std::max({idle_from_, k.not_before, now_});
  Nanos t = kNever;
  if (faults_.babbling(c, earliest) != nullptr) {
    t = earliest;
  } else if (!k.queue.empty()) {
    t = std::max(earliest, k.queue.front().given);
  }
  if (t == kNever || off_bus(c, t) || faults_.stuck(t) != nullptr) return kNever;
  return t;
}

bool WireBus::arbitrate(Nanos at) {
  if (wire_) return false;
  // Each ready controller's next frame: its queue's head, or a babbling node's frame.
  const FaultRule* best_babble = nullptr;
  const Queued* best = nullptr;
  ControllerId from = 0;
  std::uint64_t best_key = 0, best_seq = 0;
  each_sender([&](ControllerId c) {
    if (ready_at(c) != at) return;
    const FaultRule* babble = faults_.babbling(c, at);
    const std::uint64_t key = babble != nullptr ? frames::arbitration_key(babble->babble.id, babble->babble.extended,
                                                                          babble->babble.remote && !babble->babble.fd)
                                                : controllers_[c].queue.front().key;
    const std::uint64_t seq = babble != nullptr ? 0 : controllers_[c].queue.front().seq;
    if ((best != nullptr || best_babble != nullptr) && (key > best_key || (key == best_key && seq >= best_seq))) return;
    best_babble = babble;
    best = babble != nullptr ? nullptr : &controllers_[c].queue.front();
    from = c;
    best_key = key;
    best_seq = seq;
  });
  if (best == nullptr && best_babble == nullptr) return false;
  put_on_wire(from, best_key, best_babble, at);
  return true;
}

void WireBus::put_on_wire(ControllerId from, std::uint64_t key, const FaultRule* best_babble, Nanos at) {
  wire_ = OnWire{};  // small: no frame in it
  OnWire& w = *wire_;
  w.from = from;
  w.key = key;
  if (best_babble != nullptr) {
    w.babble = true;
    babble_.frame = best_babble->babble;
    babble_.key = key;
    babble_.tag = kBabbleTag;
    babble_.bits = frames::count_bits(babble_.frame);
  }
  const Queued& q = sent(w);
  const frames::WireFrame& frame = q.frame;
  w.start = at;
  recessive_run_ends(at);
  const frames::FrameBits all = q.bits;
  std::uint32_t total = all.total();
  if (config_.bits == WireConfig::Bits::kWorstCase && !frame.fd) {
    total = frames::worst_case_frame_bits(frame.remote ? 0 : frame.len, frame.extended);
  }
  if (faults_.rules().empty()) {  // only a frame nobody acknowledges fails
    w.plan = acknowledged(w.from) ? ErrorPlan{} : ErrorPlan{ErrorPlan::Cause::kAck, total - kAckSlotFromEnd};
  } else {
    w.plan = faults_.plan(frame, w.from, at, total, acknowledged(w.from));
  }
  if (w.plan.cause == ErrorPlan::Cause::kNone) {
    if (total == all.total()) {
      w.end = at + frame_bits(frames::FrameBits{all.nominal - kIntermission, all.fast});
    } else {
      w.end = at + bits(total - kIntermission);
    }
    w.free_at = w.end + bits(kIntermission);
  } else {
    w.end = at + frame_time(frame, w.plan.bit + 1);  // seen at the bit's end: the flag starts at the next
  }
  next_stale_ = true;
}

Nanos WireBus::recovery_due(const Controller& k) const noexcept {
  if (!k.recovering || wire_ || faults_.stuck(now_) != nullptr) return kNever;
  const Nanos from = std::max(recessive_from_, k.run_from);
  return from + bits(kRecoveryRunBits) * (kRecoveryOccurrences - k.occurrences);
}

void WireBus::recessive_run_ends(Nanos at) {
  if (!ever_bus_off_) return;  // nobody is recovering
  const Nanos run = bits(kRecoveryRunBits);
  for (Controller& k : controllers_) {
    if (!k.recovering) continue;
    const Nanos from = std::max(recessive_from_, k.run_from);
    if (at > from) k.occurrences += static_cast<std::uint32_t>((at - from) / run);
    k.run_from = at;
  }
}

Nanos WireBus::bus_due() const noexcept {
  if (wire_) return wire_->end;
  Nanos due = kNever;
  each_sender([&](ControllerId c) { due = std::min(due, ready_at(c)); });
  return due;
}

Nanos WireBus::earliest_due() const {
  // Calm, the next frame is chosen as soon as one is queued (choose_again),
  // and nothing else can be due: no rule, nobody bus-off or recovering.
  if (calm_) return wire_ ? wire_->end : kNever;
  Nanos next = bus_due();
  next = std::min(next, faults_.next_change());
  next = std::min(next, stuck_tick_at_);
  if (!timers_possible()) return next;
  for (ControllerId c = 0; c < controllers_.size(); ++c) {
    const Controller& k = controllers_[c];
    next = std::min({next, k.restart_at, recovery_due(k)});
    if (!k.queue.empty() && faults_.cut(c, now_)) next = std::min(next, cut_due(c));
  }
  return next;
}

void WireBus::happen(Nanos now, std::vector<WireEvent>& out) {
  while (true) {
    const Nanos due = next_event();
    if (due > now) break;
    now_ = std::max(now_, due);
    step(due, out);
    next_stale_ = true;
  }
}

void WireBus::step(Nanos at, std::vector<WireEvent>& out) {
  // One thing, the earliest; ties in this order: the wire, fault rules, timers.
  if (wire_ && wire_->end == at) {
    finish(out);
    return;
  }
  if (faults_.next_change() == at) {
    fault_change(at, out);
    return;
  }
  if (stuck_tick_at_ == at) {
    stuck_tick(at, out);
    return;
  }
  for (ControllerId c = 0; timers_possible() && c < controllers_.size(); ++c) {
    Controller& k = controllers_[c];
    if (k.restart_at == at) {
      k.restart_at = kNever;
      k.recovering = true;
      k.occurrences = 0;
      k.run_from = at;
      return;
    }
    if (recovery_due(k) == at) {
      recover(c, at, out);
      return;
    }
    if (!k.queue.empty() && faults_.cut(c, at) && cut_due(c) == at) {
      cut_attempt(c, at, out);
      return;
    }
  }
  CANHIL_DEMAND(bus_due() == at && arbitrate(at), "the wire had something due it did not do");
}

void WireBus::finish(std::vector<WireEvent>& out) {
  OnWire& w = *wire_;  // left on the wire until done: nothing here arbitrates
  if (w.plan.cause != ErrorPlan::Cause::kNone) {
    fail(w, out);
    wire_.reset();
    return;
  }
  Controller& tx = controllers_[w.from];
  stats_.busy += w.free_at - w.start;
  ++stats_.frames;
  bool changed = false;  // a counter going down changed someone's state
  bool calm_next = false;
  {
    const Queued& q = sent(w);
    WireEvent& e = out.emplace_back(w.from, q.tag, w.start, w.end, q.frame);  // before anything else goes out
    // Calm, nobody misses it and no receiver's state can change: their counts are lazy.
    bool clear = !calm_ && faults_.rules().empty();  // calm again after this frame, unless a receiver says not
    for (ControllerId c = 0; !calm_ && c < controllers_.size(); ++c) {
      Controller& k = controllers_[c];
      if (c == w.from || k.gone) continue;  // one removed is no longer on the bus: it misses nothing
      if (k.confinement.bus_off() || faults_.cut(c, w.end)) {
        e.missed.push_back(c);
        clear = false;
        continue;
      }
      k.confinement.received();
      ++k.counts.received;
      changed = changed || k.confinement.state() != k.reported;
      clear = clear && k.confinement.rec() == 0;
    }
    calm_next = clear && tx.confinement.rec() == 0;
  }
  tx.confinement.transmitted();
  ++tx.sent;
  if (calm_next) begin_calm();
  changed = changed || tx.confinement.state() != tx.reported;
  if (!w.babble) tx.queue.pop_front();
  queue_changed(w.from);
  if (tx.confinement.state() == ControllerState::kErrorPassive) {
    tx.not_before = w.free_at + bits(kSuspend);
    front_changed(w.from);
  }
  // Counters going down may change states: told after the frame, as a driver's interrupt would.
  for (ControllerId c = 0; changed && c < controllers_.size(); ++c) {
    if (controllers_[c].confinement.state() != controllers_[c].reported) report(c, w.end, 0, 0, 0, out);
  }
  idle_from_ = w.free_at;
  recessive_from_ = w.end - bits(kTailRecessive - kIntermission);
  wire_.reset();
  if (calm_) choose_again(now_);
}

void WireBus::fail(OnWire& w, std::vector<WireEvent>& out) {
  end_calm();  // counters move
  Controller& tx = controllers_[w.from];
  const ErrorPlan& plan = w.plan;
  const frames::WireBit bit = frames::bit_at(sent(w).frame, plan.bit);
  const bool passive_tx = tx.confinement.state() == ControllerState::kErrorPassive;
  bool others_flag = false;
  // The receivers: they see the transmitter's flag (a stuff or form error),
  // or, for a missing acknowledgement, an error-active transmitter's flag in
  // the ACK delimiter; an error-passive one's passive flag they do not see.
  const bool receivers_see = !(plan.cause == ErrorPlan::Cause::kAck && passive_tx);
  for (ControllerId c = 0; c < controllers_.size(); ++c) {
    if (c == w.from) continue;
    Controller& k = controllers_[c];
    if (k.confinement.bus_off() || off_bus(c, w.end) || !receivers_see) continue;
    const ControllerState before = k.confinement.state();
    k.confinement.receive_error();
    ++k.counts.errors;
    if (before != ControllerState::kErrorPassive) others_flag = true;
    const std::uint8_t kind =
        plan.cause == ErrorPlan::Cause::kBit ? frames::kProtocolErrorStuff : frames::kProtocolErrorForm;
    const std::uint8_t where =
        plan.cause == ErrorPlan::Cause::kAck ? frames::kProtocolLocationAckDelimiter : bit.location;
    report(c, w.end, frames::kErrorClassProtocol | frames::kErrorClassBusError, kind, where, out);
  }
  std::uint32_t classes = frames::kErrorClassProtocol | frames::kErrorClassBusError;
  std::uint8_t kind = frames::kProtocolErrorTx;
  TransmitError error = TransmitError::kOther;
  switch (plan.cause) {
    case ErrorPlan::Cause::kBit:
      kind |= bit.recessive ? frames::kProtocolErrorBit1 : frames::kProtocolErrorBit0;
      break;
    case ErrorPlan::Cause::kForm:
      kind |= frames::kProtocolErrorForm;
      break;
    case ErrorPlan::Cause::kAck:
      classes |= frames::kErrorClassNoAck;
      error = others_flag ? TransmitError::kOther : TransmitError::kAckNoDominant;
      break;
    case ErrorPlan::Cause::kNone:
      break;
  }
  tx.confinement.transmit_error(error);
  ++tx.counts.errors;
  ++stats_.error_frames;
  report(w.from, w.end, classes, kind, bit.location, out);
  // The others' flags, started when they see the transmitter's, end up to 6 bits after it.
  const std::uint32_t flags = kErrorFlag + (others_flag ? kErrorFlag : 0);
  w.free_at = w.end + bits(flags + kErrorDelimiter + kIntermission);
  if (tx.confinement.bus_off()) {
    if (!w.babble && !tx.queue.empty()) tx.queue.pop_front();  // the frame in its buffer is dropped
    queue_changed(w.from);
  } else if (tx.confinement.state() == ControllerState::kErrorPassive) {
    tx.not_before = w.free_at + bits(kSuspend);
    front_changed(w.from);
  }
  stats_.busy += w.free_at - w.start;
  idle_from_ = w.free_at;
  recessive_from_ = w.free_at - bits(kErrorDelimiter + kIntermission);
}

void WireBus::report(ControllerId c, Nanos at, std::uint32_t classes, std::uint8_t kind, std::uint8_t location,
                     std::vector<WireEvent>& out) {
  Controller& k = controllers_[c];
  const ControllerState state = k.confinement.state();
  if (classes == 0 && state == k.reported) return;
  WireEvent e;
  e.kind = WireEvent::Kind::kError;
  e.controller = c;
  e.at = at;
  e.start = at;
  e.error = error_frame(classes, kind, location, k.confinement, k.reported);
  if (state == ControllerState::kBusOff && k.reported != ControllerState::kBusOff) enter_bus_off(c, at);
  k.reported = state;
  out.push_back(std::move(e));
}

void WireBus::enter_bus_off(ControllerId c, Nanos at) {
  Controller& k = controllers_[c];
  ++k.counts.bus_offs;
  ever_bus_off_ = true;
  k.recovering = false;
  k.restart_at = k.options.restart_delay ? at + *k.options.restart_delay : kNever;
}

void WireBus::recover(ControllerId c, Nanos at, std::vector<WireEvent>& out) {
  Controller& k = controllers_[c];
  k.confinement.recovered();
  k.recovering = false;
  ++k.counts.restarts;
  k.not_before = at;
  front_changed(c);
  WireEvent e;
  e.kind = WireEvent::Kind::kError;
  e.controller = c;
  e.at = at;
  e.start = at;
  e.error = error_frame(frames::kErrorClassRestarted, 0, 0, k.confinement, ControllerState::kErrorActive);
  k.reported = ControllerState::kErrorActive;
  out.push_back(std::move(e));
}

bool WireBus::restart(ControllerId controller, Nanos now) {
  Controller& k = controllers_.at(controller);
  if (!k.confinement.bus_off()) return false;
  k.restart_at = std::max(now, now_);
  ever_bus_off_ = true;
  next_stale_ = true;
  return true;
}

void WireBus::set_restart_delay(ControllerId controller, std::optional<Nanos> delay) {
  controllers_.at(controller).options.restart_delay = delay;
  next_stale_ = true;
}

bool WireBus::add_fault(const FaultRule& rule) {
  const bool needs_node = rule.kind == FaultRule::Kind::kBusOff || rule.kind == FaultRule::Kind::kBabbling ||
                          rule.kind == FaultRule::Kind::kCut;
  if ((needs_node && !rule.controller) || (rule.controller && *rule.controller >= controllers_.size())) return false;
  if (calm_ && wire_ && wire_->start > now_) wire_.reset();  // chosen early, as calm allows: chosen again by the rules
  end_calm();
  faults_.add(rule, now_);
  next_stale_ = true;
  return true;
}

void WireBus::clear_faults(Nanos now) {
  faults_.clear(std::max(now, now_));
  stuck_tick_at_ = kNever;
  next_stale_ = true;
}

ControllerStatus WireBus::status(ControllerId controller) const {
  const Controller& k = controllers_.at(controller);
  ControllerStatus s = k.counts;
  s.sent = k.sent;
  s.received += calm_received(k);
  s.state = k.confinement.state();
  s.tec = k.confinement.tec();
  s.rec = k.confinement.rec();
  s.queued = k.queue.size();
  s.connected = !off_bus(controller, now_);
  s.recovering = k.recovering;
  return s;
}

}  // namespace canhil::wire
