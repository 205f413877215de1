// A bus socket's frames: every call that writes a frame (write, send, sendto,
// sendmsg, sendmmsg, writev) or reads one (read, recv, recvfrom, recvmsg,
// recvmmsg, readv, and the fortified __read_chk and company) with the
// kernel's CAN_RAW answers (net/can/raw.c's raw_sendmsg and raw_recvmsg).
// Calls on any other descriptor go on to libc unchanged.
#include <linux/can/raw.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "canhil/base/preload.hpp"
#include "preload_core.hpp"

namespace canhil::userbus::preload {
namespace {

/// raw_sendmsg for a bus socket: the frame in `iov` to the interface named
/// in `to` or the bound one.
ssize_t send_frame(int fd, Socket& s, const iovec* iov, std::size_t iovcnt, const void* to, socklen_t to_size,
                   int flags) {
  std::int32_t ifindex = s.ifindex;
  if (to != nullptr) {
    sockaddr_can a{};
    if (to_size < kMinName) return fail(EINVAL);
    if (!copy_in(&a, to, kMinName)) return fail(EFAULT);
    if (a.can_family != AF_CAN) return fail(EINVAL);
    ifindex = a.can_ifindex;
  }
  Interface* iface = interface_at(ifindex);
  if (iface == nullptr) return fail(ENXIO);
  std::size_t size = 0;
  for (std::size_t k = 0; k < iovcnt; ++k) size += iov[k].iov_len;
  const bool fd_frames = (s.flags & kFdFrames) != 0 && iface->mtu.load(std::memory_order_relaxed) == CANFD_MTU;
  if (size != CAN_MTU && !(fd_frames && size == CANFD_MTU)) return fail(EINVAL);
  TxRecord r{};
  r.at_ns = iface->driven.load(std::memory_order_relaxed) != 0 ? board_now() : -1;
  r.ifindex = ifindex;
  r.size = static_cast<std::uint32_t>(size);
  const unsigned max_length = size == CAN_MTU ? CAN_MAX_DLEN : CANFD_MAX_DLEN;
  // The record: its header here, the frame from the program's own buffers,
  // copied by the kernel in the one sendmsg (a bad buffer is its EFAULT).
  iovec parts[9];
  msghdr m{};
  m.msg_iov = parts;
  if (iovcnt <= 8 && iface->up.load(std::memory_order_relaxed) != 0) {
    parts[0] = {&r, kTxHeader};
    for (std::size_t k = 0; k < iovcnt; ++k) parts[k + 1] = iov[k];
    m.msg_iovlen = iovcnt + 1;
  } else {
    // Copied here first: a downed interface answers a bad length first (can_send's order).
    std::size_t at = 0;
    for (std::size_t k = 0; k < iovcnt; ++k) {
      if (!copy_in(r.frame + at, iov[k].iov_base, iov[k].iov_len)) return fail(EFAULT);
      at += iov[k].iov_len;
    }
    if (r.frame[offsetof(can_frame, len)] > max_length) return fail(EINVAL);
    if (iface->up.load(std::memory_order_relaxed) == 0) return fail(ENETDOWN);
    parts[0] = {&r, kTxHeader + size};
    m.msg_iovlen = 1;
  }
  // A timed interface: the frame waits in its controller's transmit queue
  // (this process's, on this interface) until the wire has sent it; a full
  // queue refuses it, as a CAN device's full qdisc does (ENOBUFS).
  Controller* controller = nullptr;
  if (iface->bit_rate.load(std::memory_order_relaxed) != 0 && iface->up.load(std::memory_order_relaxed) != 0) {
    if (State* state = bus_state(false)) {
      const std::int32_t slot = (s.flags & kOwnController) != 0 ? static_cast<std::int32_t>(&s - state->sockets) : -1;
      controller = find_controller(*state, s.pid, ifindex, slot, true);
    }
    if (controller != nullptr) {
      const std::uint32_t limit = iface->tx_queue.load(std::memory_order_relaxed);
      std::uint32_t q = controller->queued.load(std::memory_order_relaxed);
      do {
        if (q >= (limit == 0 ? 1U : limit)) {
          controller->refused.fetch_add(1, std::memory_order_relaxed);
          return fail(ENOBUFS);
        }
      } while (!controller->queued.compare_exchange_weak(q, q + 1, std::memory_order_acq_rel));
    }
  }
  const auto refund = [controller] {
    if (controller == nullptr) return;
    std::uint32_t q = controller->queued.load(std::memory_order_relaxed);
    while (q > 0 && !controller->queued.compare_exchange_weak(q, q - 1, std::memory_order_acq_rel)) {
    }
  };
  CANHIL_REAL(sendmsg);
  ssize_t n = real_sendmsg(fd, &m, MSG_NOSIGNAL | (flags & MSG_DONTWAIT));
  if (n < 0 && errno == EAGAIN) {
    // A non-blocking socket whose frames the broker has not taken yet. The
    // kernel's write delivers a vcan frame to every receiver before it
    // returns, so its queue is never full: wait for the broker as long as a
    // delivery takes, and answer ENOBUFS (a full transmit queue) only when it
    // does not take the frame within a second.
    pollfd p{fd, POLLOUT, 0};
    const timespec limit{1, 0};
    if (syscall(SYS_ppoll, &p, 1, &limit, nullptr, 8) > 0) n = real_sendmsg(fd, &m, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0 && errno == EAGAIN) errno = ENOBUFS;
  }
  if (n < 0) {
    const int e = errno;
    refund();
    errno = (e == EPIPE || e == ECONNRESET || e == ENOTCONN) ? ENXIO : e;  // ENXIO: the bus is gone
    return -1;
  }
  if (m.msg_iovlen > 1) {
    // The kernel read the frame, so its length byte is readable; the broker
    // drops a frame of a bad length too.
    std::size_t at = offsetof(can_frame, len);
    for (std::size_t k = 0; k < iovcnt; ++k) {
      if (at < iov[k].iov_len) {
        if (static_cast<const unsigned char*>(iov[k].iov_base)[at] > max_length) {
          refund();  // the broker drops it
          return fail(EINVAL);
        }
        break;
      }
      at -= iov[k].iov_len;
    }
  }
  count_sent(1);
  return static_cast<ssize_t>(size);
}

void put_cmsg(msghdr* m, cmsghdr*& at, int level, int type, const void* data, std::size_t size) {
  if (m->msg_control == nullptr) return;
  const std::size_t used =
      at == nullptr ? 0 : static_cast<std::size_t>(reinterpret_cast<char*>(at) - static_cast<char*>(m->msg_control));
  if (used + CMSG_SPACE(size) > m->msg_controllen && used + CMSG_LEN(size) > m->msg_controllen) {
    m->msg_flags |= MSG_CTRUNC;
    return;
  }
  cmsghdr* c = at == nullptr ? static_cast<cmsghdr*>(m->msg_control) : at;
  c->cmsg_level = level;
  c->cmsg_type = type;
  c->cmsg_len = CMSG_LEN(size);
  std::memcpy(CMSG_DATA(c), data, size);
  at = reinterpret_cast<cmsghdr*>(reinterpret_cast<char*>(c) + CMSG_SPACE(size));
}

/// raw_recvmsg for a bus socket: one frame into `m`'s buffers, its interface,
/// flags, time and drops.
ssize_t receive_frame(int fd, Socket& s, msghdr* m, int flags) {
  if ((flags & MSG_ERRQUEUE) != 0) return fail(EAGAIN);  // nothing is ever on it (no transmit stamps)
  if (const int e = s.pending_error.exchange(0)) return fail(e);
  // The record's header here, its frame straight into the program's buffers
  // (the kernel's copy: a bad buffer is its EFAULT, a short one MSG_TRUNC).
  RxRecord r{};
  iovec parts[9];
  msghdr in{};
  in.msg_iov = parts;
  const bool direct = m->msg_iovlen <= 8;
  if (direct) {
    parts[0] = {&r, kRxHeader};
    for (std::size_t k = 0; k < static_cast<std::size_t>(m->msg_iovlen); ++k) parts[k + 1] = m->msg_iov[k];
    in.msg_iovlen = m->msg_iovlen + 1;
  } else {
    parts[0] = {&r, sizeof r};
    in.msg_iovlen = 1;
  }
  CANHIL_REAL(recvmsg);
  const ssize_t n = real_recvmsg(fd, &in, flags & (MSG_DONTWAIT | MSG_PEEK));
  if (n < 0) return -1;
  if (n == 0) return fail(ENODEV);  // the broker went away with the bus
  if ((flags & MSG_PEEK) == 0) s.taken.fetch_add(1, std::memory_order_relaxed);
  if (static_cast<std::size_t>(n) < kRxHeader) return fail(EIO);
  if (r.error != 0) return fail(r.error);
  std::size_t size = static_cast<std::size_t>(n) - kRxHeader;
  m->msg_flags = (in.msg_flags & MSG_TRUNC) != 0 ? MSG_TRUNC : 0;
  if (!direct) {
    std::size_t room = 0;
    for (std::size_t k = 0; k < static_cast<std::size_t>(m->msg_iovlen); ++k) room += m->msg_iov[k].iov_len;
    if (room < size) {
      m->msg_flags |= MSG_TRUNC;
      size = room;
    }
    std::size_t at = 0;
    for (std::size_t k = 0; k < static_cast<std::size_t>(m->msg_iovlen) && at < size; ++k) {
      const std::size_t part = std::min(m->msg_iov[k].iov_len, size - at);
      if (!copy_out(m->msg_iov[k].iov_base, r.frame + at, part)) return fail(EFAULT);
      at += part;
    }
  }
  const std::uint32_t options = s.flags;
  // sock_recv_timestamp: a frame's time goes in a control message, or is kept
  // for SIOCGSTAMP once that was asked, or marks that a frame was read.
  if ((options & kTimestamp) == 0 && (flags & MSG_PEEK) == 0) {
    if ((options & kStampKept) != 0) {
      s.last_stamp_ns.store(r.stamp_ns, std::memory_order_relaxed);
    } else if (s.last_stamp_ns.load(std::memory_order_relaxed) < 0) {
      s.last_stamp_ns.store(0, std::memory_order_relaxed);
    }
  }
  cmsghdr* next = nullptr;
  const std::size_t control_room = m->msg_controllen;
  if ((options & kTimestamp) != 0) {
    const bool fresh = (options & kTimestampNew) != 0;
    if ((options & kTimestampNs) != 0) {
      const timespec t{r.stamp_ns / 1000000000, r.stamp_ns % 1000000000};
      put_cmsg(m, next, SOL_SOCKET, fresh ? SO_TIMESTAMPNS_NEW : SO_TIMESTAMPNS_OLD, &t, sizeof t);
    } else {
      const timeval t{r.stamp_ns / 1000000000, (r.stamp_ns % 1000000000) / 1000};
      put_cmsg(m, next, SOL_SOCKET, fresh ? SO_TIMESTAMP_NEW : SO_TIMESTAMP_OLD, &t, sizeof t);
    }
  }
  if ((options & kRxqOverflow) != 0 && r.drops != 0)
    put_cmsg(m, next, SOL_SOCKET, SO_RXQ_OVFL, &r.drops, sizeof r.drops);
  m->msg_controllen =
      next == nullptr ? 0
                      : static_cast<std::size_t>(reinterpret_cast<char*>(next) - static_cast<char*>(m->msg_control));
  if (m->msg_controllen > control_room) m->msg_controllen = control_room;
  if (m->msg_name != nullptr) {
    sockaddr_can a{};
    a.can_family = AF_CAN;
    a.can_ifindex = r.ifindex;
    const socklen_t give = m->msg_namelen < kMinName ? m->msg_namelen : kMinName;
    std::memcpy(m->msg_name, &a, give);
    m->msg_namelen = kMinName;
  }
  m->msg_flags |= static_cast<int>(r.msg_flags);
  return static_cast<ssize_t>(size);
}

ssize_t receive_into(int fd, Socket& s, void* buffer, std::size_t size, int flags, sockaddr* from,
                     socklen_t* from_size) {
  iovec v{buffer, size};
  msghdr m{};
  m.msg_iov = &v;
  m.msg_iovlen = 1;
  m.msg_name = from;
  m.msg_namelen = from_size != nullptr ? *from_size : 0;
  const ssize_t n = receive_frame(fd, s, &m, flags);
  if (n >= 0 && from != nullptr && from_size != nullptr) *from_size = m.msg_namelen;
  return n;
}

ssize_t send_from(int fd, Socket& s, const void* buffer, std::size_t size, int flags, const sockaddr* to,
                  socklen_t to_size) {
  const iovec v{const_cast<void*>(buffer), size};
  return send_frame(fd, s, &v, 1, to, to_size, flags);
}

}  // namespace
}  // namespace canhil::userbus::preload

namespace bus = canhil::userbus::preload;

#pragma GCC visibility push(default)
extern "C" {

ssize_t write(int fd, const void* buffer, size_t size) {
  if (auto* s = bus::socket_of(fd)) return bus::send_from(fd, *s, buffer, size, 0, nullptr, 0);
  CANHIL_REAL(write);
  return real_write(fd, buffer, size);
}

ssize_t send(int fd, const void* buffer, size_t size, int flags) {
  if (auto* s = bus::socket_of(fd)) return bus::send_from(fd, *s, buffer, size, flags, nullptr, 0);
  CANHIL_REAL(send);
  return real_send(fd, buffer, size, flags);
}

ssize_t sendto(int fd, const void* buffer, size_t size, int flags, const sockaddr* to, socklen_t to_size) {
  if (auto* s = bus::socket_of(fd)) return bus::send_from(fd, *s, buffer, size, flags, to, to_size);
  CANHIL_REAL(sendto);
  return real_sendto(fd, buffer, size, flags, to, to_size);
}

ssize_t sendmsg(int fd, const msghdr* m, int flags) {
  if (auto* s = bus::socket_of(fd)) {
    return bus::send_frame(fd, *s, m->msg_iov, m->msg_iovlen, m->msg_name, m->msg_namelen, flags);
  }
  CANHIL_REAL(sendmsg);
  return real_sendmsg(fd, m, flags);
}

int sendmmsg(int fd, mmsghdr* v, unsigned int n, int flags) {
  if (auto* s = bus::socket_of(fd)) {
    unsigned int sent = 0;
    for (; sent < n; ++sent) {
      const msghdr& m = v[sent].msg_hdr;
      const ssize_t r = bus::send_frame(fd, *s, m.msg_iov, m.msg_iovlen, m.msg_name, m.msg_namelen, flags);
      if (r < 0) return sent > 0 ? static_cast<int>(sent) : -1;
      v[sent].msg_len = static_cast<unsigned int>(r);
    }
    return static_cast<int>(sent);
  }
  CANHIL_REAL(sendmmsg);
  return real_sendmmsg(fd, v, n, flags);
}

ssize_t writev(int fd, const iovec* iov, int iovcnt) {
  if (auto* s = bus::socket_of(fd)) {
    if (iovcnt < 0) return bus::fail(EINVAL);
    return bus::send_frame(fd, *s, iov, static_cast<std::size_t>(iovcnt), nullptr, 0, 0);
  }
  CANHIL_REAL(writev);
  return real_writev(fd, iov, iovcnt);
}

ssize_t read(int fd, void* buffer, size_t size) {
  if (auto* s = bus::socket_of(fd)) return bus::receive_into(fd, *s, buffer, size, 0, nullptr, nullptr);
  CANHIL_REAL(read);
  return real_read(fd, buffer, size);
}

// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's fortified call, taken over as the plain one
ssize_t __read_chk(int fd, void* buffer, size_t size, size_t buffer_size) {
  if (auto* s = bus::socket_of(fd))
    return bus::receive_into(fd, *s, buffer, size < buffer_size ? size : buffer_size, 0, nullptr, nullptr);
  CANHIL_REAL(__read_chk);
  return real___read_chk(fd, buffer, size, buffer_size);
}

ssize_t recv(int fd, void* buffer, size_t size, int flags) {
  if (auto* s = bus::socket_of(fd)) return bus::receive_into(fd, *s, buffer, size, flags, nullptr, nullptr);
  CANHIL_REAL(recv);
  return real_recv(fd, buffer, size, flags);
}

// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's fortified call, taken over as the plain one
ssize_t __recv_chk(int fd, void* buffer, size_t size, size_t buffer_size, int flags) {
  if (auto* s = bus::socket_of(fd))
    return bus::receive_into(fd, *s, buffer, size < buffer_size ? size : buffer_size, flags, nullptr, nullptr);
  CANHIL_REAL(__recv_chk);
  return real___recv_chk(fd, buffer, size, buffer_size, flags);
}

ssize_t recvfrom(int fd, void* buffer, size_t size, int flags, sockaddr* from, socklen_t* from_size) {
  if (auto* s = bus::socket_of(fd)) return bus::receive_into(fd, *s, buffer, size, flags, from, from_size);
  CANHIL_REAL(recvfrom);
  return real_recvfrom(fd, buffer, size, flags, from, from_size);
}

// NOLINTNEXTLINE(bugprone-reserved-identifier): glibc's fortified call, taken over as the plain one
ssize_t __recvfrom_chk(int fd, void* buffer, size_t size, size_t buffer_size, int flags, sockaddr* from,
                       socklen_t* from_size) {
  if (auto* s = bus::socket_of(fd)) {
    return bus::receive_into(fd, *s, buffer, size < buffer_size ? size : buffer_size, flags, from, from_size);
  }
  CANHIL_REAL(__recvfrom_chk);
  return real___recvfrom_chk(fd, buffer, size, buffer_size, flags, from, from_size);
}

ssize_t recvmsg(int fd, msghdr* m, int flags) {
  if (auto* s = bus::socket_of(fd)) return bus::receive_frame(fd, *s, m, flags);
  CANHIL_REAL(recvmsg);
  return real_recvmsg(fd, m, flags);
}

int recvmmsg(int fd, mmsghdr* v, unsigned int n, int flags, timespec* timeout) {
  if (auto* s = bus::socket_of(fd)) {
    // As the kernel: the time-out is looked at after each frame, not while one is awaited.
    timespec deadline{};
    if (timeout != nullptr) {
      clock_gettime(CLOCK_MONOTONIC, &deadline);
      deadline.tv_sec += timeout->tv_sec;
      deadline.tv_nsec += timeout->tv_nsec;
      if (deadline.tv_nsec >= 1000000000) {
        deadline.tv_sec += 1;
        deadline.tv_nsec -= 1000000000;
      }
    }
    unsigned int got = 0;
    for (; got < n; ++got) {
      const int each = flags | ((got > 0 && (flags & MSG_WAITFORONE) != 0) ? MSG_DONTWAIT : 0);
      const ssize_t r = bus::receive_frame(fd, *s, &v[got].msg_hdr, each & ~MSG_WAITFORONE);
      if (r < 0) return got > 0 ? static_cast<int>(got) : -1;
      v[got].msg_len = static_cast<unsigned int>(r);
      if (timeout != nullptr) {
        timespec now{};
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (now.tv_sec > deadline.tv_sec || (now.tv_sec == deadline.tv_sec && now.tv_nsec >= deadline.tv_nsec)) {
          ++got;
          break;
        }
      }
    }
    return static_cast<int>(got);
  }
  CANHIL_REAL(recvmmsg);
  return real_recvmmsg(fd, v, n, flags, timeout);
}

ssize_t readv(int fd, const iovec* iov, int iovcnt) {
  if (auto* s = bus::socket_of(fd)) {
    if (iovcnt < 0) return bus::fail(EINVAL);
    msghdr m{};
    m.msg_iov = const_cast<iovec*>(iov);
    m.msg_iovlen = static_cast<std::size_t>(iovcnt);
    return bus::receive_frame(fd, *s, &m, 0);
  }
  CANHIL_REAL(readv);
  return real_readv(fd, iov, iovcnt);
}

}  // extern "C"
#pragma GCC visibility pop
