// canhil/can_nodes/socketcan_bus.hpp — the Bus on a SocketCAN interface.
//
// CAN_RAW, non-blocking. Received frames carry the kernel's receive timestamp
// (SO_TIMESTAMPNS, CLOCK_REALTIME). Receive-queue overflow is counted from
// SO_RXQ_OVFL. A full transmit queue (ENOBUFS/EAGAIN) is retried a bounded
// number of times with a short wait, then the frame is dropped and counted.
// An interface that goes down or vanishes is reported through state(), never
// by hanging or throwing on the hot path.
#pragma once

#include <chrono>
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
  /// receive() asks the kernel only after note_frame_on_bus() named a frame
  /// this socket's filters pass (and until the queue is empty again): a driver
  /// that sees every frame on the interface (lockstep with external processes)
  /// spares the empty reads. Off: receive() always asks.
  bool told_when_readable = false;
};

/// True when this process can open a CAN_RAW socket at all (the kernel's,
/// or canhil's user-space bus when this process runs on it).
bool kernel_has_can();

/// Which bus interface `iface` is on, for the reports: "canhil's user-space
/// bus" when this process runs on it (libcanhil-bus.so preloaded, a bus up
/// with that interface), else "the kernel's SocketCAN".
const char* bus_of(const std::string& iface);

class SocketCanBus final : public Bus {
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

  /// A frame went on this socket's interface (told_when_readable): when the
  /// socket's filters pass it, the next receive() asks the kernel again.
  void note_frame_on_bus(const CanFrame& frame) noexcept;
  /// Frames sent so far (stats().sent without asking the kernel anything).
  std::uint64_t frames_sent() const noexcept { return stats_.sent; }
  /// The socket, for poll()/epoll in a real-time loop. Owned by this object.
  int fd() const { return fd_; }
  /// Waits up to `timeout` for a frame to be readable; true if one is.
  bool wait_readable(std::chrono::microseconds timeout) const;
  /// Re-reads the interface's state from the kernel (call when idle).
  BusState refresh_state();

 private:
  SocketCanBus(int fd, std::string iface, int ifindex, const SocketCanOptions& options);
  void note_errno(int err);
  void note_drops(std::uint32_t absolute) const;
  void read_drop_counter() const;

  int fd_;
  std::string iface_;
  int ifindex_;
  SocketCanOptions options_;
  BusState state_ = BusState::kUp;
  mutable BusStats stats_;  // rx_overflow is refreshed from the kernel in const stats()
  mutable std::uint32_t last_drop_count_ = 0;
  bool read_since_drop_check_ = false;  // a frame came since the drop counter was last read
  bool may_be_readable_ = true;         // told_when_readable: a frame for us may be queued
  std::vector<Filter> filters_;         // as set, for note_frame_on_bus(); empty: every frame
  bool filters_set_empty_ = false;      // set_filters({}): no frame at all
  std::uint32_t error_mask_ = 0;
};

}  // namespace canhil::can_nodes
