#include "canhil/can_nodes/delivery_fence.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "canhil/base/errno_text.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/userbus/bus_hook.h"

namespace canhil::can_nodes {
namespace {

constexpr std::uint32_t kIdsPerSocket = 512;  // CAN_RAW_FILTER_MAX
constexpr int kReceiveBuffer = 1 << 20;

// A socket on `ifindex` that receives exactly the standard data frames with
// ids first .. first + kIdsPerSocket - 1, each through its own single-id filter.
int open_fence_socket(const std::string& iface, unsigned ifindex, std::uint32_t first) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    throw SetupError("cannot open a CAN socket for the delivery fence on " + iface + ": " + errno_text(err));
  }
  auto fail = [&](const char* what) {
    const int err = errno;
    ::close(fd);
    throw SetupError("cannot set up the delivery fence on " + iface + ": " + what + ": " + errno_text(err));
  };
  std::array<can_filter, kIdsPerSocket> filters{};
  for (std::uint32_t i = 0; i < kIdsPerSocket; ++i) {
    // The mask with both flags is what puts a filter in the kernel's single-id list.
    filters[i] = can_filter{first + i, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG};
  }
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(), sizeof filters) < 0) fail("CAN_RAW_FILTER");
  const can_err_mask_t no_errors = 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &no_errors, sizeof no_errors) < 0) fail("CAN_RAW_ERR_FILTER");
  if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &kReceiveBuffer, sizeof kReceiveBuffer) < 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &kReceiveBuffer, sizeof kReceiveBuffer) < 0) {
    fail("SO_RCVBUF");
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) fail("bind");
  return fd;
}

}  // namespace

DeliveryFence::DeliveryFence() : epoll_(::epoll_create1(EPOLL_CLOEXEC)) {
  if (epoll_ < 0) {
    const int err = errno;
    throw SetupError("cannot create an epoll instance for the delivery fence: " + errno_text(err));
  }
}

DeliveryFence::~DeliveryFence() {
  for (const Interface& i : interfaces_) {
    for (const int fd : i.sockets) ::close(fd);
  }
  ::close(epoll_);
}

std::size_t DeliveryFence::add(const std::string& iface) {
  const unsigned ifindex = if_nametoindex(iface.c_str());
  if (ifindex == 0) {
    throw SetupError("no network interface named " + iface + ": create it with `vcan_setup/vcan-up.sh " + iface + "`");
  }
  const std::size_t index = interfaces_.size();
  if (on_user_space_bus(iface)) {
    // The bus's preload, in this process; canhil does not link it.
    rounds_ = userbus::hooks().rounds;
    if (rounds_ == nullptr) {
      throw SetupError(iface +
                       " is on canhil's user-space bus, but its preload cannot tell when frames are "
                       "delivered: it is of another canhil; start this canhil's bus (`canhil bus down`, then up)");
    }
    interfaces_.emplace_back();
    return index;
  }
  Interface& added = interfaces_.emplace_back();
  for (std::uint32_t first = 0; first < kStandardIds; first += kIdsPerSocket) {
    const int fd = open_fence_socket(iface, ifindex, first);
    added.sockets.push_back(fd);
    epoll_event e{};
    e.events = EPOLLIN;
    e.data.u64 = (static_cast<std::uint64_t>(index) << 8) | (added.sockets.size() - 1);
    if (::epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &e) < 0) {
      const int err = errno;
      throw SetupError("cannot watch the delivery fence on " + iface + ": " + errno_text(err));
    }
  }
  return index;
}

void DeliveryFence::drain() {
  // Only interfaces of the user-space bus, whose reached() asks the bus: nothing to read.
  if (std::all_of(interfaces_.begin(), interfaces_.end(), [](const Interface& i) { return i.sockets.empty(); })) return;
  std::array<epoll_event, 16> ready{};
  // Only counts matter: the frames are read in batches and forgotten.
  std::array<can_frame, 64> frames{};
  std::array<mmsghdr, 64> headers{};
  std::array<iovec, 64> iov{};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    iov[i] = iovec{&frames[i], sizeof(can_frame)};
    headers[i].msg_hdr.msg_iov = &iov[i];
    headers[i].msg_hdr.msg_iovlen = 1;
  }
  int n = 0;
  do {
    n = ::epoll_wait(epoll_, ready.data(), static_cast<int>(ready.size()), 0);
    for (int e = 0; e < n; ++e) {
      const std::uint64_t key = ready[static_cast<std::size_t>(e)].data.u64;
      Interface& i = interfaces_[key >> 8];
      const int fd = i.sockets[key & 0xFF];
      for (;;) {
        const int got = ::recvmmsg(fd, headers.data(), static_cast<unsigned>(headers.size()), MSG_DONTWAIT, nullptr);
        if (got <= 0) break;
        i.delivered += static_cast<std::uint64_t>(got);
        if (got < static_cast<int>(headers.size())) break;
      }
    }
  } while (n == static_cast<int>(ready.size()));
}

bool DeliveryFence::reached(std::size_t index, std::uint64_t fenced) {
  Interface& i = interfaces_.at(index);
  if (!i.sockets.empty() || rounds_ == nullptr) return i.delivered >= fenced;
  const std::uint64_t round = rounds_();
  if (round % 2 == 0) return true;  // no round under way: every one before has ended
  if (i.odd_round == 0 || i.odd_for != fenced) {
    // The round under way may be the one handing out the latest frame read.
    i.odd_for = fenced;
    i.odd_round = round;
    return false;
  }
  return round != i.odd_round;  // that round has ended since
}

bool DeliveryFence::counts(const frames::CanFrame& frame) noexcept {
  return frame.kind == frames::FrameKind::kData && !frame.extended;
}

}  // namespace canhil::can_nodes
