// canhil/can_nodes/socketcan_bus.hpp — an Endpoint on a SocketCAN interface: one socket.
//
// CAN_RAW, non-blocking. Received frames carry the kernel's receive timestamp
// (SO_TIMESTAMPNS, CLOCK_REALTIME). Receive-queue overflow is counted from
// SO_RXQ_OVFL. A full transmit queue (ENOBUFS/EAGAIN) is retried a bounded
// number of times with a short wait, then the frame is dropped and counted.
// An interface that goes down or vanishes is reported through state(), never
// by hanging or throwing on the hot path.
#pragma once

#include <chrono>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/bus.hpp"
#include "canhil/can_nodes/clock.hpp"

namespace canhil::can_nodes {

struct SocketCanOptions {
  /// Receive own frames too (CAN_RAW_RECV_OWN_MSGS); off like SocketCAN's default.
  bool receive_own = false;
  /// Receive buffer size in bytes (SO_RCVBUF); 0 keeps the kernel default.
  int receive_buffer_bytes = 0;
  /// Receive filters set before the socket is bound, so that nothing else is
  /// ever queued (set_filters() after open() lets in what came in between).
  /// Empty: every frame, as the kernel's default.
  std::vector<Filter> filters;
  /// Attempts after a full transmit queue before a frame is dropped.
  int send_retries = 50;
  /// Longest wait for the queue to drain per retry.
  std::chrono::microseconds retry_wait{200};
  /// Received frames are timed by this clock (virtual time: the instant they
  /// are read) instead of the kernel's stamp. Must outlive the bus.
  const Clock* clock = nullptr;
  /// receive() takes only the frames feed() hands it: the kernel queues
  /// nothing on this socket (its own filters are set to none; the ones given
  /// here or by set_filters() and set_error_mask() are applied by feed(),
  /// with the kernel's rules). For a driver that reads every frame of the
  /// interface on one socket of its own (lockstep with external processes):
  /// one read per frame for all the nodes of an interface, instead of one per
  /// node that takes it, and none that finds the queue empty. Sending is as
  /// always.
  bool fed = false;
  /// When a read finds the queue empty after frames, the socket's drop
  /// counter is read (SO_MEMINFO: drops after the last frame read come with
  /// no later frame's SO_RXQ_OVFL). Off for a socket read empty at every
  /// instant whose drops show otherwise (the lockstep's observers, whose
  /// delivery fence waits for every frame sent): one system call an instant
  /// less, three on canhil's user-space bus. stats() still reads it.
  bool drops_when_empty = true;
  /// On canhil's user-space bus, a receive() that the bus's counts say would
  /// find the queue empty (waiting() false) returns at once, without the
  /// system call (the lockstep's observers, read until empty at every
  /// instant); a frame the broker is handing over at that moment is read by
  /// a later call. Only for a socket canhil watches otherwise too: a bus
  /// whose broker died reads as empty, not as gone. The kernel's SocketCAN:
  /// no effect.
  bool skips_empty_reads = false;
};

/// True when this process can open a CAN_RAW socket at all (the kernel's,
/// or canhil's user-space bus when this process runs on it).
bool kernel_has_can();

/// Whether `iface` is on canhil's user-space bus: this process runs on it
/// (libcanhil-bus.so preloaded) and the bus has that interface.
bool on_user_space_bus(const std::string& iface);

/// Which bus interface `iface` is on, for the reports: "canhil's user-space
/// bus" when this process runs on it (libcanhil-bus.so preloaded, a bus up
/// with that interface), else "the kernel's SocketCAN".
const char* bus_of(const std::string& iface);

class SocketCanBus final : public Endpoint {
 public:
  /// Opens `iface`. Throws SetupError with what to do when it cannot.
  static std::unique_ptr<SocketCanBus> open(const std::string& iface, const SocketCanOptions& options = {});
  ~SocketCanBus() override;

  SendStatus send(const CanFrame& frame) override;
  std::optional<TimedFrame> receive() override;
  /// Throws SetupError when the kernel refuses (more than 512 filters).
  void set_filters(std::span<const Filter> filters) override;
  /// Throws SetupError when the kernel refuses.
  void set_error_mask(std::uint32_t mask) override;
  BusState state() const override { return state_; }
  /// Also reads the kernel's drop counter, so rx_overflow is current.
  BusStats stats() const override;
  const std::string& name() const override { return iface_; }

  /// A frame went on this socket's interface (fed): queued for receive() when
  /// the socket's filters or error mask pass it and this socket did not send
  /// it (the kernel gives a socket its own frames only with receive_own).
  void feed(const CanFrame& frame);
  /// Frames sent so far (stats().sent without asking the kernel anything).
  std::uint64_t frames_sent() const noexcept { return stats_.sent; }
  /// The socket, for poll()/epoll in a real-time loop. Owned by this object.
  int fd() const { return fd_; }
  /// On canhil's user-space bus, whether a frame (or an error) waits to be
  /// read, from the bus's counts in memory (true: one is in the socket; false:
  /// none, or one the broker is handing over right now). On the kernel's
  /// SocketCAN, which does not say: nullopt.
  std::optional<bool> waiting() const;
  /// Empty reads skipped by skips_empty_reads, so far.
  std::uint64_t empty_reads_skipped() const noexcept { return skipped_; }
  /// Waits up to `timeout` for a frame to be readable; true if one is.
  bool wait_readable(std::chrono::microseconds timeout) const;
  /// Re-reads the interface's state from the kernel (call when idle).
  BusState refresh_state();

 private:
  SocketCanBus(int fd, std::string iface, int ifindex, const SocketCanOptions& options);
  void note_errno(int err);
  void note_drops(std::uint32_t absolute) const;
  void read_drop_counter() const;
  /// A read found the queue empty (drops_when_empty).
  void found_empty();
  std::optional<TimedFrame> take_fed();
  /// A frame given to the node: counted as an error frame or a received one.
  void count_received(const CanFrame& frame);
  /// Own frames remembered until fed back (fed); more means some were lost.
  static constexpr std::size_t kMostOwnInFlight = 4096;

  int fd_;
  std::string iface_;
  int ifindex_;
  SocketCanOptions options_;
  BusState state_ = BusState::kUp;
  mutable BusStats stats_;  // rx_overflow is refreshed from the kernel in const stats()
  mutable std::uint32_t last_drop_count_ = 0;
  bool read_since_drop_check_ = false;  // a frame came since the drop counter was last read
  std::deque<CanFrame> fed_;            // fed: the frames receive() gives next
  std::deque<CanFrame> own_;            // fed: frames this socket sent, not yet fed back
  std::vector<Filter> filters_;         // as set, for feed(); empty: every frame
  bool filters_set_empty_ = false;      // set_filters({}): no frame at all
  std::uint32_t error_mask_ = 0;
  long long (*waiting_)(int) = nullptr;  // canhil_userbus_waiting, on the user-space bus
  std::uint64_t skipped_ = 0;
};

}  // namespace canhil::can_nodes
