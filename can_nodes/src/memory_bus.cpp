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

BusState MemoryEndpoint::state() const { return bus_->up() ? BusState::kUp : BusState::kDown; }

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
  return endpoint;
}

void MemoryBus::detach(MemoryEndpoint* endpoint) {
  endpoints_.erase(std::remove(endpoints_.begin(), endpoints_.end(), endpoint), endpoints_.end());
  routes_stale_ = true;
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

void MemoryBus::transmit(MemoryEndpoint* from, const CanFrame& frame) {
  if (wire_.bit_rate != 0 && frame.kind != frames::FrameKind::kError) {
    queue(from, frame);
    return;
  }
  deliver_now(from, frame, clock_.now());
}

void MemoryBus::queue(MemoryEndpoint* from, const CanFrame& frame) {
  const Pending p{frame, from,
                  frames::arbitration_key(frame.id, frame.extended, frame.kind == frames::FrameKind::kRemote), seq_++};
  const Nanos now = clock_.now();
  if (!busy_) {
    start(p, now);
  } else if (start_ == now && p.key < on_wire_.key) {
    // Arbitration started at this very instant: the frame queued now takes part, and wins.
    pending_.push_back(on_wire_);
    start(p, now);
  } else {
    pending_.push_back(p);
  }
}

void MemoryBus::start(const Pending& p, Nanos at) {
  const CanFrame& f = p.frame;
  const std::uint32_t bits =
      wire_.bits == Wire::Bits::kExact
          ? frames::frame_bits(f)
          : frames::worst_case_frame_bits(f.kind == frames::FrameKind::kRemote ? 0 : f.len, f.extended);
  busy_ = true;
  on_wire_ = p;
  start_ = at;
  end_ = at + frames::bits_to_time(bits, wire_.bit_rate);
}

void MemoryBus::advance(Nanos now) {
  while (busy_ && end_ <= now) {
    busy_ = false;
    const Nanos end = end_;
    deliver_now(on_wire_.from, on_wire_.frame, wire_.stamp == Wire::Stamp::kStartOfFrame ? start_ : end);
    if (pending_.empty()) break;
    // The bus is idle: the lowest key wins, and among equal keys the first sent.
    const auto winner = std::min_element(pending_.begin(), pending_.end(), [](const Pending& a, const Pending& b) {
      return a.key != b.key ? a.key < b.key : a.seq < b.seq;
    });
    const Pending next = *winner;
    pending_.erase(winner);
    start(next, end);
  }
}

void MemoryBus::deliver_now(MemoryEndpoint* from, const CanFrame& frame, Nanos time) {
  ++carried_;
  const TimedFrame timed{frame, time};
  if (tap_) tap_(timed);
  if (frame.kind == frames::FrameKind::kData && !frame.extended && frame.id < kStandardIds) {
    route();
    for (std::uint32_t k = route_start_[frame.id]; k < route_start_[frame.id + 1]; ++k) {
      MemoryEndpoint* e = route_list_[k];
      if (e != from || e->receive_own_) e->accept(timed);
    }
    return;
  }
  for (MemoryEndpoint* e : endpoints_) {
    if (e != from || e->receive_own_) e->deliver(timed);
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
