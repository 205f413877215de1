#include "canhil/laptop/raw_can.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace canhil::laptop {

RawCan::RawCan(const std::string& iface) {
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    throw std::runtime_error("cannot open a CAN socket (" + std::string(std::strerror(errno)) +
                             "): this kernel has no SocketCAN; run inside vcan_setup/vm-run.sh");
  }
  const unsigned index = if_nametoindex(iface.c_str());
  if (index == 0) {
    ::close(fd_);
    throw std::runtime_error("no interface " + iface + "; create it with vcan_setup/vcan-up.sh " + iface);
  }
  const int one = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one);
  // Every error class: the controller's errors, states, bus-off and restarts
  // (the handler counts and reports them). An interface that has none sends none.
  const can_err_mask_t errors = CAN_ERR_MASK;
  ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    const int err = errno;
    ::close(fd_);
    throw std::runtime_error("cannot bind to " + iface + ": " + std::strerror(err));
  }
}

RawCan::~RawCan() { ::close(fd_); }

bool RawCan::send(const frames::CanFrame& f) {
  can_frame k{};
  k.can_id = f.extended ? (f.id | CAN_EFF_FLAG) : f.id;
  k.len = f.len;
  std::memcpy(k.data, f.data.data(), 8);
  return ::write(fd_, &k, sizeof k) == static_cast<ssize_t>(sizeof k);
}

std::optional<frames::TimedFrame> RawCan::receive() {
  can_frame k{};
  iovec iov{&k, sizeof k};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  if (::recvmsg(fd_, &msg, MSG_DONTWAIT) != static_cast<ssize_t>(sizeof k)) return std::nullopt;
  frames::TimedFrame out;
  if ((k.can_id & CAN_ERR_FLAG) != 0u) {
    out.frame.kind = frames::FrameKind::kError;
    out.frame.id = k.can_id & CAN_ERR_MASK;
  } else {
    out.frame.extended = (k.can_id & CAN_EFF_FLAG) != 0u;
    out.frame.id = k.can_id & (out.frame.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    if ((k.can_id & CAN_RTR_FLAG) != 0u) out.frame.kind = frames::FrameKind::kRemote;
  }
  out.frame.len = k.len > 8 ? 8 : k.len;
  std::memcpy(out.frame.data.data(), k.data, out.frame.len);
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      out.time = std::chrono::seconds(ts.tv_sec) + Nanos(ts.tv_nsec);
    }
  }
  return out;
}

}  // namespace canhil::laptop
