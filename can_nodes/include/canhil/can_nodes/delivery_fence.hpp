#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canhil/frames/frame.hpp"

namespace canhil::can_nodes {

/// Tells when a frame on a SocketCAN interface has reached every socket that
/// will receive it, not only the first one.
///
/// On the kernel's SocketCAN it stands on the kernel's order of serving. The
/// kernel hands a frame to its receivers one after the other, in a fixed
/// order of lists: sockets without filters first, then mask filters, inverted
/// filters and last the single-id filters of a standard data frame; within a
/// list, the latest registered first. So a socket that has a frame has said
/// nothing about a socket later in that order. The fence opens sockets with
/// one single-id filter for each of the 2048 standard ids (four sockets of
/// 512, the kernel's limit per socket) before anyone else's: for a standard
/// data frame they are served last, so once they have it, every socket on
/// that interface has it. Open it before the sockets it is to fence; a socket
/// that set its filters earlier may be served after it.
///
/// On canhil's user-space bus the bus says so itself, and the fence opens no
/// socket: its broker hands each round of frames to their sockets with a
/// count odd meanwhile (userbus::State::rounds). A frame read on one socket
/// is in every socket once that count is even, or past the odd value it had
/// after the read.
///
/// Either way, the frames fenced are standard-id data frames (counts()), so
/// that canhil waits for the same frames on both.
class DeliveryFence {
 public:
  DeliveryFence();
  ~DeliveryFence();
  DeliveryFence(const DeliveryFence&) = delete;
  DeliveryFence& operator=(const DeliveryFence&) = delete;

  /// Fences `iface` too; returns its index for reached(). SetupError as
  /// SocketCanBus::open.
  std::size_t add(const std::string& iface);
  /// Reads what has reached the fence's sockets since the last call.
  void drain();
  /// Whether the first `fenced` frames that counts() takes on interface
  /// `index`, read by the caller on a socket of its own, had reached every
  /// socket on it at the last drain() (the kernel's) or now (the bus's).
  bool reached(std::size_t index, std::uint64_t fenced);
  /// The sockets fencing interface `index`: four on the kernel's SocketCAN,
  /// none where the bus says when frames are delivered.
  std::size_t sockets(std::size_t index) const { return interfaces_.at(index).sockets.size(); }
  /// A descriptor readable while a frame waits at the kernel's fence (for
  /// poll); on the user-space bus never readable (reached() asks the bus).
  int descriptor() const noexcept { return epoll_; }
  /// Whether the fence can tell about `frame` (a standard-id data frame).
  static bool counts(const frames::CanFrame& frame) noexcept;

 private:
  struct Interface {
    std::vector<int> sockets;     // the kernel's: empty on the user-space bus
    std::uint64_t delivered = 0;  // the kernel's: fenced frames its sockets read
    // The user-space bus's: the odd round seen after the caller had read
    // `odd_for` frames (none seen: odd_round 0).
    std::uint64_t odd_for = 0;
    std::uint64_t odd_round = 0;
  };
  std::vector<Interface> interfaces_;
  int epoll_ = -1;
  // The user-space bus's rounds (canhil_userbus_rounds in its preload), once
  // an interface is on it.
  unsigned long long (*rounds_)() = nullptr;
};

}  // namespace canhil::can_nodes
