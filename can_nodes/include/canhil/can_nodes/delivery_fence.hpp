#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canhil/frames/frame.hpp"

namespace canhil::can_nodes {

/// Tells when a frame on a SocketCAN interface has reached every socket that
/// will receive it, not only the first one.
///
/// The kernel hands a frame to its receivers one after the other, in a fixed
/// order of lists: sockets without filters first, then mask filters, inverted
/// filters and last the single-id filters of a standard data frame; within a
/// list, the latest registered first. So a socket that has a frame has said
/// nothing about a socket later in that order. The fence opens sockets with
/// one single-id filter for each of the 2048 standard ids (four sockets of
/// 512, the kernel's limit per socket) before anyone else's: for a standard
/// data frame they are served last, so once they have it, every socket on
/// that interface has it. Extended, remote and error frames are not fenced
/// (counts() says which frames are).
///
/// Open it before the sockets it is to fence; a socket that set its filters
/// earlier may be served after it.
class DeliveryFence {
 public:
  DeliveryFence();
  ~DeliveryFence();
  DeliveryFence(const DeliveryFence&) = delete;
  DeliveryFence& operator=(const DeliveryFence&) = delete;

  /// Fences `iface` too; returns its index for delivered(). SetupError as
  /// SocketCanBus::open.
  std::size_t add(const std::string& iface);
  /// Reads what has reached the fence's sockets since the last call.
  void drain();
  /// Fenced frames that had reached every socket on interface `index` at the
  /// last drain(), since add().
  std::uint64_t delivered(std::size_t index) const { return interfaces_.at(index).delivered; }
  /// A descriptor readable while a frame waits at the fence (for poll).
  int descriptor() const noexcept { return epoll_; }
  /// Whether the fence can tell about `frame` (a standard-id data frame).
  static bool counts(const frames::CanFrame& frame) noexcept;

 private:
  struct Interface {
    std::vector<int> sockets;
    std::uint64_t delivered = 0;
  };
  std::vector<Interface> interfaces_;
  int epoll_ = -1;
};

}  // namespace canhil::can_nodes
