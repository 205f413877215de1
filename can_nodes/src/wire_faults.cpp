#include "canhil/can_nodes/wire_faults.hpp"

namespace canhil::can_nodes {
namespace {

wire::FaultRule::Kind kind_of(FaultKind kind) {
  switch (kind) {
    case FaultKind::kBitErrors:
      return wire::FaultRule::Kind::kBitErrors;
    case FaultKind::kNoAck:
      return wire::FaultRule::Kind::kNoAck;
    case FaultKind::kStuckDominant:
      return wire::FaultRule::Kind::kStuckDominant;
    case FaultKind::kBabbling:
      return wire::FaultRule::Kind::kBabbling;
    case FaultKind::kCut:
      return wire::FaultRule::Kind::kCut;
    case FaultKind::kBusOff:
      return wire::FaultRule::Kind::kBusOff;
    default:
      return wire::FaultRule::Kind::kFrameErrors;  // error
  }
}

}  // namespace

std::vector<wire::FaultRule> wire_rules(const std::vector<FaultRule>& rules, const frames::MessageSet& set,
                                        const ControllerOf& controller_of) {
  std::vector<wire::FaultRule> out;
  for (const FaultRule& r : rules) {
    if (!wire_only(r.kind) && r.kind != FaultKind::kErrorFrame) continue;
    wire::FaultRule w;
    w.kind = kind_of(r.kind);
    w.from = r.from;
    w.until = r.until;
    w.rate = r.kind == FaultKind::kBitErrors ? r.bit_error_rate : r.probability;
    if (r.target != "*") {
      if (const frames::MessageCodec* m = set.codec().find(r.target)) {
        w.id = m->id();
      } else if (const auto c = controller_of(r.target)) {
        w.controller = *c;
      } else {
        continue;  // a node not on this bus
      }
    }
    if (r.kind == FaultKind::kBabbling) {
      w.babble.id = r.babble_id;
      w.babble.len = 8;  // the longest classic frame, all zeros: the most stuffing
    }
    out.push_back(w);
  }
  return out;
}

}  // namespace canhil::can_nodes
