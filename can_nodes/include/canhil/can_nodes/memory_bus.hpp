// canhil/can_nodes/memory_bus.hpp — an in-process CAN bus for virtual time.
//
// A MemoryBus is a medium (medium.hpp): attach() gives endpoints (each an Endpoint). A frame
// sent on one endpoint is delivered, stamped with the injected clock's time,
// to every other attached endpoint whose filters pass it, in attach order,
// like SocketCAN with loopback on and own messages off (`receive_own` turns
// them on). Each endpoint's queue is bounded; overflow is dropped and counted.
//
// By default a frame is delivered at the instant it is sent, as vcan does (the
// shipped robot's traces). With a wire (set_wire: a bit rate) the bus has a
// real one's physics, canhil's one model of it (wire::WireBus): each endpoint
// is a controller with a transmit queue, frames wait for the wire and win or
// lose arbitration, and a frame is delivered, stamped, when its end of frame
// has passed; errors and faults (wire_bus().add_fault) count against the
// controllers, which may go error-passive and bus-off (the endpoint's state
// then reads kDown, as a can-dev interface's carrier) and report it as error
// frames to their own endpoint, where its error mask asks. The wire is then a
// participant of the virtual-time runner (wire_participant()).
//
// Deterministic; not thread-safe (virtual time runs on one thread).
#pragma once

#include <bitset>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "canhil/base/ring.hpp"
#include "canhil/can_nodes/bus.hpp"
#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/doorbell.hpp"
#include "canhil/can_nodes/medium.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/wire/wire_bus.hpp"

namespace canhil::can_nodes {

class MemoryBus;

/// 11-bit identifiers: the data frames a bus routes by table.
inline constexpr std::size_t kStandardIds = std::size_t{1} << 11;

class MemoryEndpoint final : public Endpoint {
 public:
  ~MemoryEndpoint() override;

  SendStatus send(const CanFrame& frame) override;
  std::optional<TimedFrame> receive() override;
  bool may_have_frames() const override { return head_held_ || !queue_.empty(); }
  bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) override {
    bell_ = bell;
    bell_index_ = index;
    return true;
  }
  void set_filters(std::span<const Filter> filters) override;
  void set_error_mask(std::uint32_t mask) override { error_mask_ = mask; }
  BusState state() const override;
  BusStats stats() const override { return stats_; }
  const std::string& name() const override { return name_; }

  /// Also receive this endpoint's own frames (CAN_RAW_RECV_OWN_MSGS).
  void set_receive_own(bool on) { receive_own_ = on; }
  std::size_t pending() const { return (head_held_ ? 1 : 0) + queue_.size(); }

 private:
  friend class MemoryBus;
  MemoryEndpoint(MemoryBus* bus, std::string name, std::size_t capacity);
  // A frame the bus's per-id table does not route (error, extended, remote)
  // through the filters; accept() queues one they passed.
  void deliver(const TimedFrame& frame);
  void accept(const TimedFrame& frame);

  // What a frame's delivery and receipt touch first, together (accept,
  // receive): an endpoint is visited a few times an elementary cycle, cold.
  MemoryBus* bus_;
  std::size_t capacity_;
  // The oldest waiting frame is held here, in the endpoint, when it came to an
  // empty queue (the usual case: a delivery round takes each frame at once);
  // the frames after it wait in queue_, in order.
  bool head_held_ = false;
  bool receive_own_ = false;
  wire::ControllerId controller_ = 0;  // its controller on the bus's wire, once there is one
  TimedFrame head_{};
  base::Ring<TimedFrame> queue_;
  std::uint32_t error_mask_ = 0;
  std::shared_ptr<Doorbell> bell_;  // shared: an endpoint may outlive its runner
  std::size_t bell_index_ = 0;
  BusStats stats_;
  std::string name_;
  std::vector<Filter> filters_{Filter::all()};
  std::bitset<kStandardIds> standard_data_{
      std::bitset<kStandardIds>().set()};  // the filters' verdict on each 11-bit data frame
};

class MemoryBus final : public Medium {
 public:
  /// `clock` stamps every delivered frame; it must outlive the bus.
  explicit MemoryBus(const Clock& clock, std::string name = "mem0");
  ~MemoryBus() override;
  MemoryBus(const MemoryBus&) = delete;
  MemoryBus& operator=(const MemoryBus&) = delete;

  /// A new endpoint; `queue_capacity` frames may wait before overflow drops.
  /// The endpoint must not outlive the bus.
  std::unique_ptr<MemoryEndpoint> attach(std::string endpoint_name, std::size_t queue_capacity = 4096);

  // As a Medium: open() is attach() with the default queue; set_wire() always carries it.
  MediumKind kind() const noexcept override { return MediumKind::kMemory; }
  std::unique_ptr<Endpoint> open(const std::string& name) override { return attach(name); }
  MediumCounts counts() const override;

  /// Bit-times the bus (see the top of this file); Wire{} delivers at once again.
  /// Set it before frames are sent.
  bool set_wire(const Wire& wire) override;
  /// The wire as a participant of the virtual-time runner: it delivers each
  /// frame when its end of frame has passed and starts the next arbitration.
  Participant& wire_participant() noexcept { return wire_driver_; }
  /// The wire's model (faults, controllers' states, load); nullptr without a wire.
  wire::WireBus* wire_bus() noexcept {
    wire_driver_.moved();  // a fault or a restart may move the wire's next event
    return model_.get();
  }
  const wire::WireBus* wire_bus() const noexcept { return model_.get(); }
  /// The wire's controller of `endpoint` (attached to this bus), with a wire.
  wire::ControllerId controller_of(const MemoryEndpoint& endpoint) const { return endpoint.controller_; }
  /// Frames waiting for the wire (the one on it included).
  std::size_t queued() const noexcept { return model_ ? model_->queued() : 0; }

  /// Puts an error frame on the bus (delivered to endpoints whose error mask matches).
  void inject_error(std::uint32_t error_class);
  /// Takes the bus down (sends fail with kDown, nothing is delivered) or back up.
  void set_up(bool up);
  bool up() const { return up_; }
  const std::string& name() const { return name_; }
  std::uint64_t frames_carried() const { return carried_; }
  /// A passive listener (a trace, a frame count, a timing check): sees every
  /// frame the bus carries and every error frame put on it, in order, stamped
  /// as an endpoint's copy would be, as it is carried and without an
  /// endpoint's queue. One at a time; an empty function removes it.
  void set_tap(std::function<void(const TimedFrame&)> tap) { tap_ = std::move(tap); }

 private:
  friend class MemoryEndpoint;
  void transmit(MemoryEndpoint* from, const CanFrame& frame);
  void detach(MemoryEndpoint* endpoint);

  void route();  // rebuilds routes_ when stale
  // `missed`: endpoints that do not get it (bus-off or cut off the wire).
  void deliver_now(MemoryEndpoint* from, const CanFrame& frame, Nanos time,
                   const std::vector<wire::ControllerId>* missed = nullptr);

  // The wire's next event moves when a frame is given to it, a controller
  // comes or goes, or anyone is handed the model: each rings the driver's
  // doorbell, and the runner, polling it, reads its wake-up again (kept, not
  // asked for at every instant).
  class WireDriver final : public Participant {
   public:
    explicit WireDriver(MemoryBus& bus) : bus_(bus) {}
    std::size_t poll() override { return 0; }
    void tick(Nanos now) override { bus_.advance(now); }
    Nanos next_wakeup() const override { return bus_.model_ ? bus_.model_->next_event() : kNever; }
    bool may_have_frames() const override { return false; }
    bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) override {
      bell_ = bell;
      index_ = index;
      return true;
    }
    bool wakeup_is_own() const override { return true; }
    void moved() const {
      if (bell_) bell_->ring(index_);
    }

   private:
    MemoryBus& bus_;
    std::shared_ptr<Doorbell> bell_;
    std::size_t index_ = 0;
  };
  // Runs the wire to `now` and hands out what happened.
  void advance(Nanos now);
  MemoryEndpoint* endpoint_of(wire::ControllerId controller) const;

  // What a frame's sending and delivery read first, in the first three
  // cache lines; the wire's part first (each frame on a timed wire visits
  // the bus twice: given, and delivered).
  const Clock& clock_;
  std::unique_ptr<wire::WireBus> model_;      // with a wire
  std::vector<MemoryEndpoint*> controllers_;  // each controller's endpoint (nullptr once detached)
  std::vector<wire::WireEvent> events_;       // advance()'s, reused
  // Per 11-bit data frame id, the endpoints whose filters take it, in attach
  // order: a frame visits only those, route_list_[route_start_[id]] up to
  // route_list_[route_start_[id + 1]]. Rebuilt after attach, detach or new filters.
  std::vector<std::uint32_t> route_start_;
  std::vector<MemoryEndpoint*> route_list_;
  bool routes_stale_ = true;
  bool up_ = true;
  bool stamp_at_start_ = false;  // wire_.stamp: a frame's receive stamp at its first bit
  std::uint64_t carried_ = 0;
  std::function<void(const TimedFrame&)> tap_;
  std::string name_;
  std::vector<MemoryEndpoint*> endpoints_;
  Wire wire_;
  WireDriver wire_driver_{*this};
};

}  // namespace canhil::can_nodes
