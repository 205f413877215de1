#include "canhil/wire/wire_fault.hpp"

#include "bit_counts.hpp"

#include <algorithm>
#include <cmath>

namespace canhil::wire {
namespace {

bool holds(const FaultRule& r, Nanos t) noexcept { return r.from <= t && t < r.until; }

bool matches(const FaultRule& r, const frames::WireFrame& f, ControllerId from) noexcept {
  if (r.id && (*r.id != f.id)) return false;
  return !r.controller || *r.controller == from;
}

using bit_counts::kAckSlotFromEnd;
constexpr std::uint32_t kTail = bit_counts::kAfterCrc;

}  // namespace

const char* fault_kind_name(FaultRule::Kind kind) noexcept {
  switch (kind) {
    case FaultRule::Kind::kBitErrors:
      return "bit-errors";
    case FaultRule::Kind::kFrameErrors:
      return "frame-errors";
    case FaultRule::Kind::kNoAck:
      return "no-ack";
    case FaultRule::Kind::kStuckDominant:
      return "stuck-dominant";
    case FaultRule::Kind::kBabbling:
      return "babbling";
    case FaultRule::Kind::kCut:
      return "cut";
    case FaultRule::Kind::kBusOff:
      return "bus-off";
  }
  return "?";
}

void Faults::add(FaultRule rule, Nanos now) {
  rule.from = std::max(rule.from, now);
  rule.until = std::max(rule.until, rule.from);
  rules_.push_back(rule);
  taken_.push_back({});
}

std::vector<const FaultRule*> Faults::take_starts(Nanos at) {
  std::vector<const FaultRule*> out;
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    if (!taken_[i].started && rules_[i].from <= at) {
      taken_[i].started = true;
      out.push_back(&rules_[i]);
    }
  }
  return out;
}

std::vector<const FaultRule*> Faults::take_ends(Nanos at) {
  std::vector<const FaultRule*> out;
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    if (taken_[i].started && !taken_[i].ended && rules_[i].until <= at) {
      taken_[i].ended = true;
      out.push_back(&rules_[i]);
    }
  }
  return out;
}

void Faults::clear(Nanos now) {
  for (FaultRule& r : rules_) {
    if (r.until > now) r.until = std::max(now, r.from);
  }
}

ErrorPlan Faults::plan(const frames::WireFrame& frame, ControllerId from, Nanos start, std::uint32_t total_bits,
                       bool receivers) {
  ErrorPlan plan;
  const std::uint32_t ack_slot = total_bits - kAckSlotFromEnd;
  const std::uint32_t eof_end = total_bits - 3;  // intermission bits carry no frame
  std::uint32_t first = eof_end;                 // the first bit hit, eof_end: none
  for (const FaultRule& r : rules_) {
    if (!holds(r, start)) continue;
    if (r.kind == FaultRule::Kind::kBitErrors && r.rate > 0) {
      // The first flipped bit: geometric with the per-bit rate.
      const double u = 1.0 - uniform();  // (0, 1]
      const double k = r.rate >= 1.0 ? 0.0 : std::floor(std::log(u) / std::log1p(-r.rate));
      if (k < static_cast<double>(first)) first = static_cast<std::uint32_t>(k);
    } else if (r.kind == FaultRule::Kind::kFrameErrors && matches(r, frame, from)) {
      if (r.rate < 1.0 && uniform() >= r.rate) continue;
      const std::uint32_t region = total_bits - kTail;  // SOF .. the CRC's last bit
      const auto k = static_cast<std::uint32_t>(uniform() * region);
      if (k < first) first = k;
    } else if (r.kind == FaultRule::Kind::kNoAck && matches(r, frame, from)) {
      receivers = false;
    }
  }
  if (first < ack_slot) {
    plan.cause = first < total_bits - kTail ? ErrorPlan::Cause::kBit : ErrorPlan::Cause::kForm;  // CRC delimiter: form
    plan.bit = first;
  } else if (first == ack_slot || !receivers) {
    plan.cause = ErrorPlan::Cause::kAck;  // a flipped acknowledgement reads as none
    plan.bit = ack_slot;
  } else if (first < eof_end) {
    plan.cause = ErrorPlan::Cause::kForm;
    plan.bit = first;
  }
  return plan;
}

bool Faults::cut_by_rule(ControllerId controller, Nanos t) const noexcept {
  for (const FaultRule& r : rules_) {
    if (r.kind == FaultRule::Kind::kCut && r.controller == controller && holds(r, t)) return true;
  }
  return false;
}

const FaultRule* Faults::stuck_by_rule(Nanos t) const noexcept {
  for (const FaultRule& r : rules_) {
    if (r.kind == FaultRule::Kind::kStuckDominant && holds(r, t)) return &r;
  }
  return nullptr;
}

const FaultRule* Faults::babbling_by_rule(ControllerId controller, Nanos t) const noexcept {
  for (const FaultRule& r : rules_) {
    if (r.kind == FaultRule::Kind::kBabbling && r.controller == controller && holds(r, t)) return &r;
  }
  return nullptr;
}

Nanos Faults::next_change_of_rules() const noexcept {
  Nanos next = kNever;
  for (std::size_t i = 0; i < rules_.size(); ++i) {
    if (!taken_[i].started) next = std::min(next, rules_[i].from);
    if (!taken_[i].ended) next = std::min(next, rules_[i].until);
  }
  return next;
}

}  // namespace canhil::wire
