// tests/support/laptop_endpoint.hpp — a test participant playing the laptop on
// a memory bus: records every frame with its time and, when asked, sends
// M6_1 + M6_2 in their synchronous slots like an FTT slave.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::test {

class LaptopEndpoint final : public can_nodes::Participant {
 public:
  LaptopEndpoint(can_nodes::MemoryBus& bus, std::shared_ptr<const frames::MessageSet> set, Nanos ec)
      : endpoint_(bus.attach("laptop", 1 << 16)), set_(std::move(set)), ec_(ec) {}

  /// Velocity sent in the M6 slots; nullopt sends nothing (silence).
  std::optional<frames::M6_1> m6_1;
  frames::M6_2 m6_2{};

  std::size_t poll() override {
    std::size_t n = 0;
    while (auto f = endpoint_->receive()) {
      ++n;
      frames_.push_back(*f);
      frames::Tm tm;
      if (frames::is_message(f->frame, set_->tm.message()) && set_->tm.decode(f->frame, tm).ok()) {
        const std::uint32_t mine =
            (1u << set_->ftt(set_->m6_1.message()).index) | (1u << set_->ftt(set_->m6_2.message()).index);
        if (const auto start = sync_.on_tm(tm, f->time, ec_, mine); start && m6_1) slot_ = *start;
      }
    }
    return n;
  }
  void tick(Nanos) override {
    slot_ = kNever;
    if (!m6_1) return;
    send(set_->m6_1.encode(*m6_1));
    m6_2.seq = seq_++;
    send(set_->m6_2.encode(m6_2));
  }
  Nanos next_wakeup() const override { return slot_; }

  void send(const frames::CanFrame& f) {
    endpoint_->send(f);
    ++sent_;
  }
  std::uint64_t sent_count() const { return sent_; }
  const std::vector<frames::TimedFrame>& frames() const { return frames_; }
  /// Frames with this id, in order.
  std::vector<frames::TimedFrame> with_id(std::uint32_t id) const {
    std::vector<frames::TimedFrame> out;
    for (const auto& f : frames_) {
      if (f.frame.id == id && f.frame.kind == frames::FrameKind::kData) out.push_back(f);
    }
    return out;
  }
  template <class T>
  std::vector<T> decoded(const frames::TypedCodec<T>& codec) const {
    std::vector<T> out;
    for (const auto& f : with_id(codec.message().id())) {
      T v;
      if (codec.decode(f.frame, v).ok()) out.push_back(v);
    }
    return out;
  }

 private:
  std::unique_ptr<can_nodes::MemoryEndpoint> endpoint_;
  std::shared_ptr<const frames::MessageSet> set_;
  Nanos ec_;
  frames::SyncSlot sync_;
  Nanos slot_ = kNever;
  std::uint8_t seq_ = 0;
  std::uint64_t sent_ = 0;
  std::vector<frames::TimedFrame> frames_;
};

}  // namespace canhil::test
