// WireBus: the moments of its fault rules (a rule starting or ending, a
// stuck-dominant bus's 8-bit sequences, a cut-off controller's attempts on
// its own stub of cable).
#include <algorithm>

#include "bit_counts.hpp"
#include "canhil/wire/wire_bus.hpp"

namespace canhil::wire {
using namespace bit_counts;  // NOLINT(google-build-using-namespace)

void WireBus::fault_change(Nanos at, std::vector<WireEvent>& out) {
  for (const FaultRule* r : faults_.take_starts(at)) {
    switch (r->kind) {
      case FaultRule::Kind::kBusOff: {
        const ControllerId c = *r->controller;
        if (wire_ && wire_->from == c) {
          // Its frame stops where it is; the others see the bus fall idle.
          stats_.busy += at - wire_->start;
          idle_from_ = at + bits(kBusIdle);
          recessive_from_ = at;
          if (!wire_->babble && !controllers_[c].queue.empty()) {
            controllers_[c].queue.pop_front();
            queue_changed(c);
            ++controllers_[c].counts.lost;
          }
          wire_.reset();
        }
        controllers_[c].confinement.force_tec(kBusOffLimit);
        report(c, at, 0, 0, 0, out);
        break;
      }
      case FaultRule::Kind::kStuckDominant:
        if (wire_) {
          // The frame on the wire meets a dominant bit it did not send.
          const frames::WireFrame& frame = sent(*wire_).frame;
          const std::uint32_t total = frames::count_bits(frame).total();
          std::uint32_t bit = 0;
          while (bit + 1 < total && wire_->start + frame_time(frame, bit + 1) <= at) ++bit;
          wire_->plan = ErrorPlan{ErrorPlan::Cause::kBit, bit};
          wire_->end = at;
          OnWire w = *wire_;
          wire_.reset();
          fail(w, out);
        }
        recessive_run_ends(at);
        idle_from_ = kNever;
        stuck_tick_at_ = at + bits(kFirstDominantSequence);
        break;
      case FaultRule::Kind::kCut:
        if (r->controller) controllers_[*r->controller].cut_busy_until = at;
        break;
      default:
        break;
    }
  }
  for (const FaultRule* r : faults_.take_ends(at)) {
    if (r->kind == FaultRule::Kind::kStuckDominant && faults_.stuck(at) == nullptr) {
      stuck_tick_at_ = kNever;
      idle_from_ = at + bits(kBusIdle);
      recessive_from_ = at;
    }
  }
}

void WireBus::stuck_tick(Nanos at, std::vector<WireEvent>& out) {
  bool more = false;
  for (ControllerId c = 0; c < controllers_.size(); ++c) {
    Controller& k = controllers_[c];
    if (k.confinement.bus_off() || off_bus(c, at)) continue;
    const bool transmitter = !k.queue.empty() || faults_.babbling(c, at) != nullptr;
    k.confinement.dominant_sequence(transmitter);
    report(c, at, 0, 0, 0, out);
    if ((transmitter && !k.confinement.bus_off()) || k.confinement.rec() < kRecCeiling) more = true;
  }
  stuck_tick_at_ = more ? at + bits(kDominantSequence) : kNever;
}

Nanos WireBus::cut_due(ControllerId c) const noexcept {
  const Controller& k = controllers_[c];
  if (k.queue.empty() || k.confinement.bus_off()) return kNever;
  const Queued& head = k.queue.front();
  const Nanos t = std::max({k.cut_busy_until, head.given, k.not_before});
  const std::uint32_t ack_slot = frames::count_bits(head.frame).total() - kAckSlotFromEnd;
  return t + frame_time(head.frame, ack_slot + 1);
}

void WireBus::cut_attempt(ControllerId c, Nanos at, std::vector<WireEvent>& out) {
  // Alone on its stub of cable: nobody acknowledges, nobody superposes a flag.
  Controller& k = controllers_[c];
  k.confinement.transmit_error(TransmitError::kAckNoDominant);
  ++k.counts.errors;
  report(c, at, frames::kErrorClassProtocol | frames::kErrorClassBusError | frames::kErrorClassNoAck,
         frames::kProtocolErrorTx, frames::kProtocolLocationAck, out);
  k.cut_busy_until = at + bits(kErrorFlag + kErrorDelimiter + kIntermission);
  if (k.confinement.state() == ControllerState::kErrorPassive) {
    k.not_before = k.cut_busy_until + bits(kSuspend);
    front_changed(c);
  }
}

}  // namespace canhil::wire
