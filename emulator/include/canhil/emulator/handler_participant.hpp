// canhil/emulator/handler_participant.hpp — the reference low-level handler
// (laptop::HwComm) as a virtual-time participant on a memory bus: what the
// virtual run gives every robot, and what the handler's own tests drive.
#pragma once

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/laptop/hwcomm.hpp"

namespace canhil::emulator {

class HandlerParticipant final : public can_nodes::Participant {
 public:
  /// The handler of agent `space` in `db`, its items in `layout` (as
  /// laptop::HwComm takes them); `keep_sent` keeps a copy of every frame it
  /// sends (tests), otherwise nothing grows.
  HandlerParticipant(can_nodes::MemoryBus& bus, std::shared_ptr<const frames::MessageSet> set, Nanos ec,
                     const can_nodes::Clock& clock, rtdb::Database& db, const rtdb::Layout& layout, int space,
                     bool keep_sent = false)
      : ep_(bus.attach("handler", 1 << 16)),
        keep_sent_(keep_sent),
        clock_(clock),
        hw_(
            std::move(set), ec, [this](const frames::CanFrame& f) { return send(f); }, [&clock] { return clock.now(); },
            db, layout, space) {
    ep_->set_error_mask(frames::kErrorClassMask);  // as canhil-hwcomm's socket: its controller's errors too
  }

  std::size_t poll() override {
    std::size_t n = 0;
    while (auto f = ep_->receive()) {
      ++n;
      hw_.on_frame(f->frame, f->time);
    }
    return n;
  }
  bool may_have_frames() const override { return ep_->may_have_frames(); }
  bool set_doorbell(const std::shared_ptr<can_nodes::Doorbell>& bell, std::size_t index) override {
    return ep_->set_doorbell(bell, index);
  }
  /// The handler's deadlines move only as it handles frames and time.
  bool wakeup_is_own() const override { return true; }
  void tick(Nanos now) override {
    while (!delayed_.empty() && delayed_.front().first <= now) {
      const frames::CanFrame f = delayed_.front().second;
      delayed_.erase(delayed_.begin());
      send_now(f);
    }
    hw_.on_time(now);
  }
  Nanos next_wakeup() const override {
    return delayed_.empty() ? hw_.next_deadline() : std::min(hw_.next_deadline(), delayed_.front().first);
  }
  /// The robot's fault rules on what the handler sends, as on a node's frames
  /// (can_nodes/fault.hpp: rules naming `laptop` or one of its messages):
  /// dropped, delayed, corrupted, duplicated, an error frame first. The
  /// handler is not told: it believes the frame sent, as a program whose
  /// frames the bus loses. nullptr: none.
  void set_fault_hook(can_nodes::FaultHook* hook) noexcept { hook_ = hook; }

  laptop::HwComm& hw() noexcept { return hw_; }
  /// Its place on the bus (its controller, on a timed wire).
  const can_nodes::MemoryEndpoint& endpoint() const noexcept { return *ep_; }
  const laptop::HwComm& hw() const noexcept { return hw_; }
  /// Every frame sent, when kept.
  const std::vector<frames::CanFrame>& sent() const noexcept { return sent_; }

 private:
  bool send(const frames::CanFrame& f) {
    if (hook_ == nullptr) return send_now(f);
    const Nanos now = clock_.now();
    const can_nodes::FaultDecision d = hook_->on_send(can_nodes::kLaptopTarget, f, now);
    if (d.drop) return true;
    if (d.error_frame) ep_->send(frames::make_bus_error_frame());
    frames::CanFrame out = f;
    if (d.corrupt_byte >= 0 && d.corrupt_byte < 8) out.data[static_cast<std::size_t>(d.corrupt_byte)] ^= d.corrupt_mask;
    bool sent = true;
    for (int copy = 0; copy <= d.duplicates; ++copy) {
      if (d.delay > Nanos{0}) {
        const Nanos due = now + d.delay;
        delayed_.insert(
            std::upper_bound(delayed_.begin(), delayed_.end(), due, [](Nanos t, const auto& e) { return t < e.first; }),
            {due, out});
      } else {
        sent = send_now(out) && sent;
      }
    }
    return sent;
  }
  bool send_now(const frames::CanFrame& f) {
    if (keep_sent_) sent_.push_back(f);
    return ep_->send(f) == can_nodes::SendStatus::kOk;
  }

  std::unique_ptr<can_nodes::MemoryEndpoint> ep_;
  bool keep_sent_;
  std::vector<frames::CanFrame> sent_;
  const can_nodes::Clock& clock_;
  can_nodes::FaultHook* hook_ = nullptr;
  std::vector<std::pair<Nanos, frames::CanFrame>> delayed_;  // by due time
  laptop::HwComm hw_;
};

}  // namespace canhil::emulator
