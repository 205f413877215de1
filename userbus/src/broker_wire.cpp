// The broker's timed interfaces (broker_wire.hpp): the wire model in real time.
#include "broker_wire.hpp"

#include <linux/can/error.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <deque>
#include <optional>
#include <string>

#include "canhil/base/time.hpp"
#include "canhil/frames/wire.hpp"
#include "canhil/userbus/state.hpp"
#include "canhil/wire/wire_bus.hpp"

namespace canhil::userbus {
namespace {

// A stamp or drive time this far past the wire's own is nobody's instant (a
// hostile or broken request): a frame so stamped is taken now, a drive ignored.
constexpr std::int64_t kFarAhead = 3600LL * 1'000'000'000;

/// The wire's view of a frame as a program wrote it (an FD length the DLC
/// cannot carry takes the next one up, as a controller pads it).
frames::WireFrame wire_frame_of(const unsigned char* raw, std::uint32_t size) {
  canfd_frame f{};
  std::memcpy(&f, raw, size);
  frames::WireFrame w;
  w.extended = (f.can_id & CAN_EFF_FLAG) != 0;
  w.id = f.can_id & (w.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  if (size == CANFD_MTU) {
    w.fd = true;
    w.brs = (f.flags & CANFD_BRS) != 0;
    w.esi = (f.flags & CANFD_ESI) != 0;
    w.len = frames::fd_length(frames::fd_dlc(std::min<std::uint8_t>(f.len, CANFD_MAX_DLEN)));
  } else {
    const auto& c = reinterpret_cast<const can_frame&>(f);
    w.remote = (c.can_id & CAN_RTR_FLAG) != 0;
    w.len = std::min<std::uint8_t>(c.len, CAN_MAX_DLEN);
    w.len8_dlc = c.len == CAN_MAX_DLEN && c.len8_dlc > CAN_MAX_DLEN ? c.len8_dlc : 0;
  }
  std::copy(f.data, f.data + w.len, w.data.begin());
  return w;
}

/// A babbling fault's frame, as a program would read it.
void raw_of(const frames::WireFrame& w, WireDelivery& d) {
  can_frame f{};
  f.can_id = w.id | (w.extended ? CAN_EFF_FLAG : 0U) | (w.remote ? CAN_RTR_FLAG : 0U);
  f.len = std::min<std::uint8_t>(w.len, CAN_MAX_DLEN);
  std::copy(w.data.begin(), w.data.begin() + f.len, f.data);
  d.size = CAN_MTU;
  std::memcpy(d.frame, &f, sizeof f);
}

std::optional<Nanos> restart_delay(std::int32_t ms) {
  if (ms <= 0) return std::nullopt;  // as the kernel's restart-ms 0: only on request
  return Nanos{static_cast<std::int64_t>(ms) * 1'000'000};
}

}  // namespace

struct BrokerWire::Wire {
  std::int32_t ifindex = 0;
  std::uint32_t bit_rate = 0;
  std::uint32_t data_bit_rate = 0;
  std::int32_t restart_ms = 0;
  std::int64_t origin = 0;  // monotonic ns at the wire's time 0
  bool driven = false;      // its clock a lockstep run's: at `driven_now`, moved by drive()
  std::int64_t driven_now = 0;
  std::unique_ptr<wire::WireBus> bus;
  // A frame as its program wrote it, waiting in its controller's queue.
  struct Given {
    std::uint64_t tag = 0;  // its connection
    std::uint32_t size = 0;
    unsigned char frame[CANFD_MTU];
  };
  struct Member {
    ControllerKey key;
    bool leaving = false;  // its process has gone: it leaves once its queue is empty
    bool gone = false;
    // Its frames in the model's queue, in the same order: a controller sends
    // its own first to last, so the front is the one the wire ends or loses.
    std::deque<Given> given;
    std::uint64_t lost = 0;  // ControllerStatus::lost, as last seen
  };
  std::vector<Member> members;  // by ControllerId
  std::vector<wire::WireEvent> events;

  Nanos at(std::int64_t now) const { return Nanos{driven ? driven_now : std::max<std::int64_t>(now - origin, 0)}; }
  std::optional<wire::ControllerId> controller_of(ControllerKey key) const {
    for (std::size_t k = 0; k < members.size(); ++k) {
      if (!members[k].gone && members[k].key == key) return static_cast<wire::ControllerId>(k);
    }
    return std::nullopt;
  }
  ControllerKey key_of(wire::ControllerId c) const { return c < members.size() ? members[c].key : ControllerKey{}; }
};

BrokerWire::BrokerWire(State& state) : state_(state), wires_(kMaxInterfaces) {}
BrokerWire::~BrokerWire() = default;

BrokerWire::Wire* BrokerWire::wire_of(std::int32_t ifindex) const noexcept {
  const int k = ifindex - kFirstIndex;
  if (k < 0 || k >= kMaxInterfaces) return nullptr;
  return wires_[static_cast<std::size_t>(k)].get();
}

bool BrokerWire::timed(std::int32_t ifindex) const noexcept { return wire_of(ifindex) != nullptr; }

void BrokerWire::sync(std::int64_t now) {
  for (int k = 0; k < kMaxInterfaces; ++k) {
    const Interface& i = state_.interfaces[k];
    const bool exists = i.in_use.load(std::memory_order_acquire) != 0;
    const std::uint32_t rate = exists ? i.bit_rate.load() : 0;
    const std::uint32_t data_rate = exists ? i.data_bit_rate.load() : 0;
    const std::int32_t restart_ms = i.restart_ms.load();
    const bool driven = exists && i.driven.load() != 0;
    std::unique_ptr<Wire>& w = wires_[static_cast<std::size_t>(k)];
    if (w && w->bit_rate == rate && w->data_bit_rate == data_rate && w->driven == driven) {
      if (w->restart_ms != restart_ms) {
        w->restart_ms = restart_ms;
        for (std::size_t c = 0; c < w->members.size(); ++c)
          if (!w->members[c].gone)
            w->bus->set_restart_delay(static_cast<wire::ControllerId>(c), restart_delay(restart_ms));
      }
      continue;
    }
    // A new wire, or none: what waited on the old one is dropped, as when a
    // CAN interface is set down to change its bit timing.
    // Its controllers go with it (those of a new wire join as their sockets send).
    for (Controller& row : state_.controllers) {
      if (row.in_use.load(std::memory_order_acquire) == 0 || row.ifindex != kFirstIndex + k) continue;
      row.queued.store(0);
      row.in_use.store(0, std::memory_order_release);
    }
    w.reset();
    if (rate == 0) continue;
    w = std::make_unique<Wire>();
    w->ifindex = kFirstIndex + k;
    w->bit_rate = rate;
    w->data_bit_rate = data_rate;
    w->restart_ms = restart_ms;
    w->origin = now;
    w->driven = driven;
    wire::WireConfig config;
    config.bit_rate = rate;
    config.data_bit_rate = data_rate;
    w->bus = std::make_unique<wire::WireBus>(config);
  }
}

Controller* BrokerWire::row(ControllerKey key, std::int32_t ifindex, bool claim) {
  return find_controller(state_, key.pid, ifindex, key.slot, claim);
}

void BrokerWire::join(ControllerKey key, std::int32_t ifindex) {
  Wire* w = wire_of(ifindex);
  if (w == nullptr) return;
  if (const auto id = w->controller_of(key)) {
    w->members[*id].leaving = false;  // its process has a socket there again
    return;
  }
  wire::ControllerOptions options;
  options.queue_frames = 1U << 20;  // the preload keeps each at the interface's tx_queue
  options.restart_delay = restart_delay(w->restart_ms);
  const wire::ControllerId id = w->bus->add_controller(
      "pid " + std::to_string(key.pid) + (key.slot >= 0 ? " socket " + std::to_string(key.slot) : ""), options);
  if (w->members.size() <= id) w->members.resize(id + 1);
  w->members[id] = Wire::Member{};
  w->members[id].key = key;
  row(key, ifindex, true);
}

void BrokerWire::leave(ControllerKey key) {
  for (std::unique_ptr<Wire>& w : wires_) {
    if (!w) continue;
    if (const auto id = w->controller_of(key)) w->members[*id].leaving = true;
    retire(*w);
  }
}

void BrokerWire::refund(ControllerKey key, std::int32_t ifindex) {
  if (Wire* w = wire_of(ifindex)) release(*w, key, 1);
}

// `n` frames of `pid`'s have left its transmit queue: room for the preload.
void BrokerWire::release(Wire& w, ControllerKey key, std::uint32_t n) {
  Controller* r = row(key, w.ifindex, false);
  if (r == nullptr) return;
  std::uint32_t q = r->queued.load(std::memory_order_relaxed);
  while (!r->queued.compare_exchange_weak(q, q - std::min(q, n), std::memory_order_acq_rel)) {
  }
}

// Frames the wire lost (ControllerStatus::lost: the one on the wire when its
// controller was forced bus-off) leave their queue too: the front one.
void BrokerWire::account_losses(Wire& w) {
  for (std::size_t k = 0; k < w.members.size(); ++k) {
    Wire::Member& m = w.members[k];
    if (m.gone) continue;
    const std::uint64_t lost = w.bus->status(static_cast<wire::ControllerId>(k)).lost;
    if (lost == m.lost) continue;
    release(w, m.key, static_cast<std::uint32_t>(lost - m.lost));
    for (; m.lost < lost && !m.given.empty(); ++m.lost) m.given.pop_front();
    m.lost = lost;
  }
}

std::size_t BrokerWire::live_members(const Wire& w) {
  return static_cast<std::size_t>(
      std::count_if(w.members.begin(), w.members.end(), [](const Wire::Member& m) { return !m.gone; }));
}

// Controllers whose process has gone leave once their queue is empty: what
// a program wrote before it closed its socket is on its way, as frames in a
// CAN device's queue outlive the socket that gave them.
void BrokerWire::retire(Wire& w) {
  for (std::size_t k = 0; k < w.members.size(); ++k) {
    Wire::Member& m = w.members[k];
    if (m.gone || !m.leaving) continue;
    // Its queue sent, or nothing will ever send it: bus-off, or
    // unacknowledged (error-passive, nobody else on the wire).
    const wire::ControllerStatus st = w.bus->status(static_cast<wire::ControllerId>(k));
    const bool stuck = st.state == frames::ControllerState::kBusOff ||
                       (st.state == frames::ControllerState::kErrorPassive && live_members(w) <= 1);
    if (st.queued != 0 && !stuck) continue;
    m.given.clear();
    w.bus->remove_controller(static_cast<wire::ControllerId>(k));
    m.gone = true;
    if (Controller* r = row(m.key, w.ifindex, false)) r->in_use.store(0, std::memory_order_release);
  }
}

void BrokerWire::submit(ControllerKey key, std::uint64_t tag, const TxRecord& record, std::int64_t now,
                        std::vector<WireDelivery>& out) {
  Wire* w = wire_of(record.ifindex);
  if (w == nullptr) return;
  if (w->driven && record.at_ns > w->driven_now && record.at_ns - w->driven_now < kFarAhead) {
    // Written at a later instant of the run than the wire has been run to:
    // it is run there first (normally nothing is due: the run drove it).
    w->driven_now = record.at_ns;
    collect(*w, now, out);
  }
  join(key, record.ifindex);
  const wire::ControllerId id = *w->controller_of(key);
  Wire::Given& g = w->members[id].given.emplace_back();
  g.tag = tag;
  g.size = record.size;
  std::memcpy(g.frame, record.frame, record.size);
  w->bus->submit(id, wire_frame_of(record.frame, record.size), w->at(now), tag);
  publish_due(*w);
}

std::int64_t BrokerWire::next_due() const noexcept {
  std::int64_t due = INT64_MAX;
  for (const std::unique_ptr<Wire>& w : wires_) {
    if (!w || w->driven) continue;  // a driven wire's time is the run's: drive()
    const Nanos next = w->bus->next_event();
    if (next != kNever) due = std::min(due, w->origin + next.count());
  }
  return due;
}

void BrokerWire::drive(std::int32_t ifindex, std::int64_t time_ns, std::vector<WireDelivery>& out) {
  Wire* w = wire_of(ifindex);
  if (w == nullptr || !w->driven || time_ns - w->driven_now > kFarAhead) return;
  w->driven_now = std::max(w->driven_now, time_ns);
  collect(*w, 0, out);
}

void BrokerWire::advance(std::int64_t now, std::vector<WireDelivery>& out) {
  for (std::unique_ptr<Wire>& wp : wires_) {
    if (!wp || wp->driven) continue;
    const Nanos next = wp->bus->next_event();
    if (next == kNever || wp->origin + next.count() > now) continue;
    collect(*wp, now, out);
  }
}

// What wire `w` did up to `now` (its own time when driven), as deliveries.
void BrokerWire::collect(Wire& w, std::int64_t now, std::vector<WireDelivery>& out) {
  Interface* iface = find_interface(state_, w.ifindex);
  w.events.clear();
  w.bus->advance(w.at(now), w.events);
  for (const wire::WireEvent& e : w.events) {
    WireDelivery& d = out.emplace_back();
    d.ifindex = w.ifindex;
    d.at_ns = w.origin + e.at.count();
    if (e.kind == wire::WireEvent::Kind::kError) {
      d.error = true;
      d.from = w.key_of(e.controller);
      can_frame f{};
      f.can_id = CAN_ERR_FLAG | (e.error.id & CAN_ERR_MASK);
      f.len = CAN_ERR_DLC;
      std::copy(e.error.data.begin(), e.error.data.end(), f.data);
      d.size = CAN_MTU;
      std::memcpy(d.frame, &f, sizeof f);
      continue;
    }
    for (const wire::ControllerId m : e.missed) d.missed.push_back(w.key_of(m));
    if (iface != nullptr) iface->delivered.fetch_add(1, std::memory_order_relaxed);
    std::deque<Wire::Given>* given = e.controller < w.members.size() ? &w.members[e.controller].given : nullptr;
    if (e.tag == wire::kBabbleTag || given == nullptr || given->empty()) {
      raw_of(e.frame, d);  // a babbling fault's own frame
      continue;
    }
    const Wire::Given& g = given->front();
    d.from = w.members[e.controller].key;
    d.tag = g.tag;
    d.size = g.size;
    std::memcpy(d.frame, g.frame, d.size);
    given->pop_front();
    release(w, d.from, 1);
  }
  account_losses(w);
  retire(w);
  publish(w, now);
}

void BrokerWire::publish(Wire& w, std::int64_t now) {
  for (std::size_t k = 0; k < w.members.size(); ++k) {
    if (w.members[k].gone) continue;
    Controller* row = this->row(w.members[k].key, w.ifindex, false);
    if (row == nullptr) continue;
    const wire::ControllerStatus s = w.bus->status(static_cast<wire::ControllerId>(k));
    row->state.store(static_cast<std::uint32_t>(s.state), std::memory_order_relaxed);
    row->tec.store(s.tec, std::memory_order_relaxed);
    row->rec.store(s.rec, std::memory_order_relaxed);
    row->sent.store(s.sent, std::memory_order_relaxed);
    row->received.store(s.received, std::memory_order_relaxed);
    row->errors.store(s.errors, std::memory_order_relaxed);
    row->bus_offs.store(s.bus_offs, std::memory_order_relaxed);
    row->restarts.store(s.restarts, std::memory_order_relaxed);
  }
  if (Interface* i = find_interface(state_, w.ifindex)) {
    i->busy_ns.store(static_cast<std::uint64_t>(w.bus->stats().busy.count()), std::memory_order_relaxed);
    i->wire_ns.store(static_cast<std::uint64_t>(w.at(now).count()), std::memory_order_relaxed);
    i->error_frames.store(w.bus->stats().error_frames, std::memory_order_relaxed);
  }
  publish_due(w);
}

void BrokerWire::publish_due(Wire& w) {
  Interface* i = find_interface(state_, w.ifindex);
  if (i == nullptr) return;
  const Nanos next = w.bus->next_event();
  i->next_due_ns.store(next == kNever ? INT64_MAX : next.count(), std::memory_order_release);
}

int BrokerWire::control(const ControlRequest& r, std::int64_t now, std::vector<WireDelivery>& out) {
  switch (r.op) {
    case kControlRestart:
      return restart(r.ifindex, r.pid, now);
    case kControlFault:
      return add_fault(r.ifindex, r.fault, now);
    case kControlClearFaults:
      return clear_faults(r.ifindex, now);
    case kControlWireTime:
      drive(r.ifindex, r.time_ns, out);
      return 0;
    default:
      return -EINVAL;
  }
}

int BrokerWire::restart(std::int32_t ifindex, std::int32_t pid, std::int64_t now) {
  Wire* w = wire_of(ifindex);
  if (w == nullptr) return -EINVAL;  // as the kernel: restart needs a CAN device
  bool any = false;
  for (std::size_t k = 0; k < w->members.size(); ++k) {
    if (w->members[k].gone || (pid != 0 && w->members[k].key.pid != pid)) continue;
    any = w->bus->restart(static_cast<wire::ControllerId>(k), w->at(now)) || any;
  }
  return any ? 0 : -EBUSY;  // can_restart_now: EBUSY when the device is not bus-off
}

int BrokerWire::add_fault(std::int32_t ifindex, const FaultRequest& f, std::int64_t now) {
  Wire* w = wire_of(ifindex);
  if (w == nullptr) return -EINVAL;
  if (f.kind > static_cast<std::uint32_t>(wire::FaultRule::Kind::kBusOff)) return -EINVAL;
  wire::FaultRule rule;
  rule.kind = static_cast<wire::FaultRule::Kind>(f.kind);
  constexpr std::int64_t kYear = 365LL * 24 * 3600 * 1'000'000'000;  // later than that: for ever
  rule.from = w->at(now) + Nanos{std::clamp<std::int64_t>(f.from_ns, 0, kYear)};
  rule.until = f.until_ns < 0 || f.until_ns > kYear ? kNever : w->at(now) + Nanos{f.until_ns};
  rule.rate = f.rate;
  if (f.has_id != 0) rule.id = f.id;
  if (f.pid != 0) {
    rule.controller = w->controller_of(ControllerKey{f.pid, f.slot});
    if (!rule.controller) return -ESRCH;
  }
  if (rule.kind == wire::FaultRule::Kind::kBabbling) {
    rule.babble.id = f.babble_id & CAN_SFF_MASK;
    rule.babble.len = 8;
  }
  return w->bus->add_fault(rule) ? 0 : -EINVAL;
}

int BrokerWire::clear_faults(std::int32_t ifindex, std::int64_t now) {
  Wire* w = wire_of(ifindex);
  if (w == nullptr) return -EINVAL;
  w->bus->clear_faults(w->at(now));
  return 0;
}

}  // namespace canhil::userbus
