#include "canhil/can_nodes/memory_bus.hpp"

#include <algorithm>

#include "canhil/base/demand.hpp"
#include "canhil/frames/wire.hpp"

namespace canhil::can_nodes {

MemoryEndpoint::MemoryEndpoint(MemoryBus* bus, std::string name, std::size_t capacity)
    : bus_(bus), capacity_(capacity), name_(std::move(name)) {}

MemoryEndpoint::~MemoryEndpoint() {
  if (bus_ != nullptr) bus_->detach(this);
}

SendStatus MemoryEndpoint::send(const CanFrame& frame) {
  if (!bus_->up()) return SendStatus::kDown;
  if (bus_->model_ && frame.kind != frames::FrameKind::kError) {
    bus_->wire_driver_.moved();
    bus_->advance(bus_->clock_.now());
    const auto queued = bus_->model_->submit(controller_, frame, bus_->clock_.now());
    if (queued == wire::WireBus::Submit::kQueueFull) {
      ++stats_.send_dropped;  // the socket's ENOBUFS
      return SendStatus::kDropped;
    }
    ++stats_.sent;
    return SendStatus::kOk;
  }
  ++stats_.sent;
  bus_->transmit(this, frame);
  return SendStatus::kOk;
}

std::optional<TimedFrame> MemoryEndpoint::receive() {
  if (head_held_) {
    head_held_ = false;
    return head_;
  }
  if (queue_.empty()) return std::nullopt;
  TimedFrame f = queue_.front();
  queue_.pop_front();
  return f;
}

void MemoryEndpoint::set_filters(std::span<const Filter> filters) {
  if (bus_ != nullptr) bus_->routes_stale_ = true;
  filters_.assign(filters.begin(), filters.end());
  // The verdict on every 11-bit data frame, filter by filter: Filter::matches
  // for a frame with that id, neither extended nor remote.
  standard_data_.reset();
  for (const Filter& f : filters_) {
    for (std::uint32_t id = 0; id < standard_data_.size(); ++id) {
      if (f.matches_standard_data(id)) standard_data_.set(id);
    }
  }
}

BusState MemoryEndpoint::state() const {
  if (!bus_->up()) return BusState::kDown;
  // Bus-off: as a can-dev interface, its carrier is off until it recovers.
  if (bus_->model_ && bus_->model_->status(controller_).state == wire::ControllerState::kBusOff) return BusState::kDown;
  return BusState::kUp;
}

void MemoryEndpoint::deliver(const TimedFrame& frame) {
  const CanFrame& f = frame.frame;
  if (f.kind == frames::FrameKind::kError) {
    if ((f.id & error_mask_) == 0) return;
  } else if (std::none_of(filters_.begin(), filters_.end(), [&](const Filter& filter) { return filter.matches(f); })) {
    return;
  }
  accept(frame);
}

void MemoryEndpoint::accept(const TimedFrame& frame) {
  if (pending() >= capacity_) {
    ++stats_.rx_overflow;
    return;
  }
  if (frame.frame.kind == frames::FrameKind::kError) {
    ++stats_.errors;
  } else {
    ++stats_.received;
  }
  if (!head_held_ && queue_.empty()) {
    head_ = frame;
    head_held_ = true;
  } else {
    queue_.push_back(frame);
  }
  if (bell_ != nullptr) bell_->ring(bell_index_);
}

MemoryBus::MemoryBus(const Clock& clock, std::string name) : clock_(clock), name_(std::move(name)) {}

MemoryBus::~MemoryBus() {
  for (MemoryEndpoint* e : endpoints_) e->bus_ = nullptr;
}

std::unique_ptr<MemoryEndpoint> MemoryBus::attach(std::string endpoint_name, std::size_t queue_capacity) {
  auto endpoint = std::unique_ptr<MemoryEndpoint>(new MemoryEndpoint(this, std::move(endpoint_name), queue_capacity));
  endpoints_.push_back(endpoint.get());
  routes_stale_ = true;
  if (model_) {
    endpoint->controller_ = model_->add_controller(endpoint->name(), wire_.controller);
    controllers_.push_back(endpoint.get());
    wire_driver_.moved();
  }
  return endpoint;
}

void MemoryBus::detach(MemoryEndpoint* endpoint) {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), endpoint), endpoints_.end());
  routes_stale_ = true;
  if (model_) {
    model_->remove_controller(endpoint->controller_);
    controllers_[endpoint->controller_] = nullptr;
    wire_driver_.moved();
  }
}

bool MemoryBus::set_wire(const Wire& wire) {
  wire_ = wire;
  stamp_at_start_ = wire.stamp == Wire::Stamp::kStartOfFrame;
  model_.reset();
  controllers_.clear();
  wire_driver_.moved();
  if (wire.bit_rate == 0) return true;
  wire::WireConfig config;
  config.bit_rate = wire.bit_rate;
  config.data_bit_rate = wire.data_bit_rate;
  config.bits = wire.bits == Wire::Bits::kExact ? wire::WireConfig::Bits::kExact : wire::WireConfig::Bits::kWorstCase;
  config.seed = wire.seed;
  model_ = std::make_unique<wire::WireBus>(config);
  for (MemoryEndpoint* e : endpoints_) {
    e->controller_ = model_->add_controller(e->name(), wire.controller);
    controllers_.push_back(e);
  }
  return true;
}

MediumCounts MemoryBus::counts() const {
  MediumCounts c;
  c.frames = carried_;
  c.timed = model_ != nullptr;
  if (model_) {
    c.error_frames = model_->stats().error_frames;
    c.load = model_->stats().load();
  }
  return c;
}

MemoryEndpoint* MemoryBus::endpoint_of(wire::ControllerId controller) const {
  return controller < controllers_.size() ? controllers_[controller] : nullptr;
}

void MemoryBus::route() {
  if (!routes_stale_) return;
  // One list of endpoints, id after id; route_start_[id] is where id's begin.
  route_start_.assign(kStandardIds + 1, 0);
  route_list_.clear();
  for (std::size_t id = 0; id < kStandardIds; ++id) {
    route_start_[id] = static_cast<std::uint32_t>(route_list_.size());
    for (MemoryEndpoint* e : endpoints_) {
      if (e->standard_data_[id]) route_list_.push_back(e);
    }
  }
  route_start_[kStandardIds] = static_cast<std::uint32_t>(route_list_.size());
  routes_stale_ = false;
}

void MemoryBus::transmit(MemoryEndpoint* from, const CanFrame& frame) { deliver_now(from, frame, clock_.now()); }

void MemoryBus::advance(Nanos now) {
  if (!model_) return;
  events_.clear();
  model_->advance(now, events_);
  for (const wire::WireEvent& e : events_) {
    MemoryEndpoint* endpoint = endpoint_of(e.controller);
    if (e.kind == wire::WireEvent::Kind::kError) {
      const TimedFrame timed{e.error, e.at};
      if (tap_) tap_(timed);
      if (endpoint != nullptr) endpoint->deliver(timed);
      continue;
    }
    CanFrame f;
    f.id = e.frame.id;
    f.extended = e.frame.extended;
    f.kind = e.frame.remote ? frames::FrameKind::kRemote : frames::FrameKind::kData;
    f.len = e.frame.len;
    f.len8_dlc = e.frame.len8_dlc;
    std::copy_n(e.frame.data.begin(), f.data.size(), f.data.begin());
    deliver_now(endpoint, f, stamp_at_start_ ? e.start : e.at, &e.missed);
  }
}

void MemoryBus::deliver_now(MemoryEndpoint* from, const CanFrame& frame, Nanos time,
                            const std::vector<wire::ControllerId>* missed) {
  ++carried_;
  const TimedFrame timed{frame, time};
  if (tap_) tap_(timed);
  const bool some_missed = missed != nullptr && !missed->empty();
  auto gets = [&](const MemoryEndpoint* e) {
    if (e == from && !e->receive_own_) return false;
    return !some_missed || std::find(missed->begin(), missed->end(), e->controller_) == missed->end();
  };
  if (frame.kind == frames::FrameKind::kData && !frame.extended && frame.id < kStandardIds) {
    route();
    for (std::uint32_t k = route_start_[frame.id]; k < route_start_[frame.id + 1]; ++k) {
      MemoryEndpoint* e = route_list_[k];
      if (gets(e)) e->accept(timed);
    }
    return;
  }
  for (MemoryEndpoint* e : endpoints_) {
    if (gets(e)) e->deliver(timed);
  }
}

void MemoryBus::inject_error(std::uint32_t error_class) {
  if (!up_) return;
  CanFrame f;
  f.kind = frames::FrameKind::kError;
  f.id = error_class & frames::kErrorClassMask;
  f.len = frames::kMaxDataBytes;
  const TimedFrame timed{f, clock_.now()};
  if (tap_) tap_(timed);
  for (MemoryEndpoint* e : endpoints_) e->deliver(timed);
}

void MemoryBus::set_up(bool up) {
  if (up == up_) return;
  up_ = up;
  for (MemoryEndpoint* e : endpoints_) ++e->stats_.state_changes;
}

}  // namespace canhil::can_nodes
