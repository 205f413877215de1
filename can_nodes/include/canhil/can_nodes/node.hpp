// canhil/can_nodes/node.hpp — what every emulated microcontroller has in common.
//
// One node, one class: a node reacts to frames (on_frame) and to time (step),
// and emits only through its bus. It declares its wake-ups (wake_at) instead of
// sleeping, so the same code runs in virtual time (a runner calls tick() at
// each wake-up) and in real time (a loop sleeps until next_wakeup()).
//
// Bad traffic is counted, never thrown: a frame of the wrong length or with a
// value out of its range is counted and dropped; the node keeps going. A node
// can be switched off (it neither hears nor speaks), and its outgoing frames
// pass an optional FaultHook (drop, delay, corrupt, duplicate).
//
// Not thread-safe: a node is driven from one thread.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <memory_resource>
#include <string>
#include <vector>

#include "canhil/can_nodes/bus.hpp"
#include "canhil/can_nodes/clock.hpp"
#include "canhil/frames/messages.hpp"

namespace canhil::can_nodes {

struct NodeCounters {
  std::uint64_t received = 0;       ///< frames handled
  std::uint64_t sent = 0;           ///< frames handed to the bus
  std::uint64_t send_failed = 0;    ///< the bus refused (down, queue full)
  std::uint64_t wrong_length = 0;   ///< a consumed message with the wrong length
  std::uint64_t out_of_range = 0;   ///< a consumed message with a value outside its range
  std::uint64_t unknown_id = 0;     ///< an id the message set does not know (counted by listeners of all ids)
  std::uint64_t fault_dropped = 0;  ///< outgoing frames a fault hook dropped
  std::uint64_t error_frames = 0;   ///< error frames a fault hook put on the bus
  std::uint64_t triggers = 0;       ///< well-formed trigger messages handled
  std::uint64_t bad_frames() const noexcept { return wrong_length + out_of_range + unknown_id; }
};

/// What to do with one outgoing frame.
struct FaultDecision {
  bool drop = false;
  Nanos delay{0};
  int corrupt_byte = -1;  ///< 0..7: this byte is XORed with corrupt_mask
  std::uint8_t corrupt_mask = 0xFF;
  int duplicates = 0;  ///< extra copies sent right after
  /// An error frame goes on the bus first, destroying the frame; it is sent
  /// again after `delay` (the controller's automatic retransmission).
  bool error_frame = false;
};

class FaultHook {
 public:
  virtual ~FaultHook() = default;
  virtual FaultDecision on_send(const std::string& node, const frames::CanFrame& frame, Nanos now) = 0;
};

class Node {
 public:
  Node(std::string name, Endpoint& bus, std::shared_ptr<const frames::MessageSet> set);
  virtual ~Node() = default;
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const noexcept { return name_; }
  /// Handles every frame waiting on the bus; returns how many.
  std::size_t poll();
  /// False only when poll() would certainly find nothing to read.
  bool may_have_frames() const { return bus_.may_have_frames() || more_may_have_frames(); }
  /// Rings `bell` with `index` when a frame arrives on anything poll() reads
  /// (Endpoint::set_doorbell); false when some of it cannot ring.
  bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) {
    const bool mine = bus_.set_doorbell(bell, index);
    return more_set_doorbell(bell, index) && mine;
  }
  /// Handles at most `max_frames` waiting frames; the rest stay queued.
  std::size_t poll(std::size_t max_frames);
  /// Acts at `now` (call when now >= next_wakeup()).
  void tick(Nanos now);
  /// The earliest time the node wants tick(); kNever when none.
  Nanos next_wakeup() const noexcept { return next_; }

  void set_enabled(bool on) noexcept { enabled_ = on; }
  bool enabled() const noexcept { return enabled_; }
  /// The hook must outlive the node; nullptr removes it.
  void set_fault_hook(FaultHook* hook) noexcept { hook_ = hook; }
  const NodeCounters& counters() const noexcept { return counters_; }
  Endpoint& bus() noexcept { return bus_; }
  const Endpoint& bus() const noexcept { return bus_; }

 protected:
  virtual void on_frame(const frames::TimedFrame& frame) = 0;
  virtual void step(Nanos now) = 0;
  /// A node with a second socket reads it here, at most `max_frames`; returns how many.
  virtual std::size_t poll_more(std::size_t max_frames) {
    (void)max_frames;
    return 0;
  }
  /// As Endpoint::may_have_frames, for what poll_more reads.
  virtual bool more_may_have_frames() const { return false; }
  /// As Endpoint::set_doorbell, for what poll_more reads (nothing: true).
  virtual bool more_set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) {
    (void)bell;
    (void)index;
    return true;
  }

  /// Asks for a tick at `t`. Every request is kept until served (a node may
  /// want its motor tick and its synchronous window); one tick serves all due.
  void wake_at(Nanos t);
  /// Sends through the fault hook.
  void emit(const frames::CanFrame& frame, Nanos now);
  /// Decodes a consumed message, counting what is wrong; true when usable.
  template <class T>
  bool decode(const frames::TypedCodec<T>& codec, const frames::CanFrame& frame, T& out) {
    const frames::DecodeResult r = codec.decode(frame, out);
    if (r.status == frames::DecodeStatus::kWrongLength) {
      ++counters_.wrong_length;
      return false;
    }
    if (r.status != frames::DecodeStatus::kOk) return false;
    if (r.out_of_range != 0) {
      ++counters_.out_of_range;
      return false;
    }
    return true;
  }
  void count_unknown() noexcept { ++counters_.unknown_id; }
  const frames::MessageSet& messages() const noexcept { return *set_; }

 private:
  void send_now(frames::CanFrame frame);

  void note_next() noexcept;  // next_ from wakes_ and delayed_

  // What poll(), tick() and next_wakeup() read come first, together: a node
  // is visited a few times an elementary cycle, its lines cold each time.
  Endpoint& bus_;
  bool enabled_ = true;
  std::uint8_t tm_length_;
  const frames::MessageCodec* tm_;  // the trigger message, in set_
  Nanos next_ = kNever;             // the earlier of wakes_'s first and delayed_'s first
  FaultHook* hook_ = nullptr;
  NodeCounters counters_;
  // Requested wake-ups, ascending. A node has a few at a time (its slot, its
  // tick, a time-out): up to kWakesInside of them live in the node itself.
  static constexpr std::size_t kWakesInside = 8;
  alignas(Nanos) std::array<std::byte, kWakesInside * sizeof(Nanos)> wake_space_;
  std::pmr::monotonic_buffer_resource wake_arena_{wake_space_.data(), wake_space_.size()};
  std::pmr::vector<Nanos> wakes_{&wake_arena_};
  std::vector<std::pair<Nanos, frames::CanFrame>> delayed_;  // by due time (fault delays; rare)
  std::shared_ptr<const frames::MessageSet> set_;
  std::string name_;
};

}  // namespace canhil::can_nodes
