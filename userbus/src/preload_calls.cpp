// A bus socket's life and options: socket, bind, close and the dup family,
// setsockopt and getsockopt (SOL_CAN_RAW and the SOL_SOCKET options CAN_RAW
// programs use), getsockname, ioctl (time stamps here, the interface calls in
// preload_interfaces.cpp), each with the kernel's answers (net/can/raw.c,
// net/core/sock.c). Other descriptors go on to libc unchanged.
#include <fcntl.h>
#include <linux/can/raw.h>
#include <linux/capability.h>
#include <linux/sock_diag.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "canhil/base/preload.hpp"
#include "preload_core.hpp"

namespace canhil::userbus::preload {
namespace {

constexpr int kMinRcvbuf = 2304;  // SOCK_MIN_RCVBUF
constexpr int kMinSndbuf = 4608;  // SOCK_MIN_SNDBUF

/// /proc/sys/net/core/`name` (rmem_default, wmem_max, ...), read once per
/// name by its caller; the kernel's usual 212992 when it cannot be read.
int net_core(const char* name) {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/sys/net/core/%s", name);
  const int fd = static_cast<int>(syscall(SYS_openat, -100, path, 0));
  if (fd < 0) return 212992;
  char text[32] = {};
  const long n = syscall(SYS_read, fd, text, sizeof text - 1);
  syscall(SYS_close, fd);
  char* end = nullptr;
  const long value = n > 0 ? std::strtol(text, &end, 10) : 0;
  return (n > 0 && end != text && value > 0 && value < (1L << 30)) ? static_cast<int>(value) : 212992;
}

int rmem_default() {
  static const int v = net_core("rmem_default");
  return v;
}
int wmem_default() {
  static const int v = net_core("wmem_default");
  return v;
}
int rmem_max() {
  static const int v = net_core("rmem_max");
  return v;
}
int wmem_max() {
  static const int v = net_core("wmem_max");
  return v;
}

bool can_net_admin() {
  __user_cap_header_struct header{_LINUX_CAPABILITY_VERSION_3, 0};
  __user_cap_data_struct data[2] = {};
  if (syscall(SYS_capget, &header, data) != 0) return false;
  return (data[0].effective & (1U << CAP_NET_ADMIN)) != 0;
}

/// Changes socket `s`'s options under its lock, the broker told by its seq.
template <class F>
void update(Socket& s, F change) {
  s.lock.lock();
  s.seq.fetch_add(1, std::memory_order_acq_rel);
  change();
  s.seq.fetch_add(1, std::memory_order_release);
  s.lock.unlock();
}

int bind_socket(Socket& s, const sockaddr* address, socklen_t size) {
  sockaddr_can a{};
  if (size < kMinName) return fail(EINVAL);
  if (size > sizeof(sockaddr_storage)) return fail(EINVAL);
  if (!copy_in(&a, address, kMinName)) return fail(EFAULT);
  if (a.can_family != AF_CAN) return fail(EINVAL);
  bool down = false;
  if (a.can_ifindex != 0) {
    const Interface* i = interface_at(a.can_ifindex);
    if (i == nullptr) return fail(ENODEV);
    down = i->up.load() == 0;
  }
  update(s, [&] {
    s.ifindex = a.can_ifindex;
    s.bound = 1;
  });
  if (down) s.pending_error.store(ENETDOWN);  // raw_bind: bound, and told the interface is down
  return 0;
}

void set_flag(Socket& s, std::uint32_t flag, bool on) {
  update(s, [&] { s.flags = on ? (s.flags | flag) : (s.flags & ~flag); });
}

int set_raw_option(Socket& s, int name, const void* value, socklen_t size) {
  switch (name) {
    case CAN_RAW_FILTER: {
      if (size % sizeof(can_filter) != 0) return fail(EINVAL);
      if (size > kMaxFilters * sizeof(can_filter)) return fail(EINVAL);
      can_filter filters[kMaxFilters];
      const std::uint32_t count = size / sizeof(can_filter);
      if (!copy_in(filters, value, size)) return fail(EFAULT);
      update(s, [&] {
        std::memcpy(s.filters, filters, size);
        s.filter_count = count;
      });
      return 0;
    }
    case CAN_RAW_ERR_FILTER: {
      can_err_mask_t mask = 0;
      if (size != sizeof mask) return fail(EINVAL);
      if (!copy_in(&mask, value, sizeof mask)) return fail(EFAULT);
      update(s, [&] { s.err_mask = mask & CAN_ERR_MASK; });
      return 0;
    }
    case CAN_RAW_LOOPBACK:
    case CAN_RAW_RECV_OWN_MSGS:
    case CAN_RAW_FD_FRAMES:
    case CAN_RAW_JOIN_FILTERS: {
      int on = 0;
      if (size != sizeof on) return fail(EINVAL);
      if (!copy_in(&on, value, sizeof on)) return fail(EFAULT);
      const std::uint32_t flag = name == CAN_RAW_LOOPBACK        ? kLoopback
                                 : name == CAN_RAW_RECV_OWN_MSGS ? kRecvOwn
                                 : name == CAN_RAW_FD_FRAMES     ? kFdFrames
                                                                 : kJoinFilters;
      set_flag(s, flag, on != 0);
      return 0;
    }
    default:
      return fail(ENOPROTOOPT);
  }
}

/// SOL_SOCKET options the bus answers itself (time stamps, drops, buffers);
/// 1 when `name` is not one of them.
int set_socket_option(int fd, Socket& s, int name, const void* value, socklen_t size) {
  switch (name) {
    case SO_TIMESTAMP_OLD:
    case SO_TIMESTAMP_NEW:
    case SO_TIMESTAMPNS_OLD:
    case SO_TIMESTAMPNS_NEW:
    case SO_RXQ_OVFL:
    case SO_RCVBUF:
    case SO_RCVBUFFORCE:
    case SO_SNDBUF:
    case SO_SNDBUFFORCE:
      break;
    default:
      return 1;
  }
  int v = 0;
  if (size < static_cast<socklen_t>(sizeof v)) return fail(EINVAL);
  if (!copy_in(&v, value, sizeof v)) return fail(EFAULT);
  switch (name) {
    case SO_TIMESTAMP_OLD:
    case SO_TIMESTAMP_NEW:
    case SO_TIMESTAMPNS_OLD:
    case SO_TIMESTAMPNS_NEW: {
      const bool ns = name == SO_TIMESTAMPNS_OLD || name == SO_TIMESTAMPNS_NEW;
      const bool fresh = name == SO_TIMESTAMP_NEW || name == SO_TIMESTAMPNS_NEW;
      update(s, [&] {
        std::uint32_t f = s.flags;
        f = ns ? (f | kTimestampNs) : (f & ~kTimestampNs);  // sock_set_timestamp
        if (v != 0) {
          f = fresh ? (f | kTimestampNew) : (f & ~kTimestampNew);
          f |= kTimestamp | kStampKept;
        } else {
          f &= ~(kTimestamp | kTimestampNs);
        }
        s.flags = f;
      });
      return 0;
    }
    case SO_RXQ_OVFL:
      set_flag(s, kRxqOverflow, v != 0);
      return 0;
    case SO_RCVBUFFORCE:
    case SO_SNDBUFFORCE:
      if (!can_net_admin()) return fail(EPERM);
      v = v < 0 ? 0 : v;
      break;
    default: {
      const unsigned cap = static_cast<unsigned>(name == SO_RCVBUF ? rmem_max() : wmem_max());
      v = static_cast<int>(static_cast<unsigned>(v) < cap ? static_cast<unsigned>(v) : cap);
      break;
    }
  }
  const bool receive = name == SO_RCVBUF || name == SO_RCVBUFFORCE;
  const int doubled = (v > 0x3fffffff ? 0x3fffffff : v) * 2;
  update(s, [&] {
    if (receive) {
      s.rcvbuf = doubled > kMinRcvbuf ? doubled : kMinRcvbuf;
    } else {
      s.sndbuf = doubled > kMinSndbuf ? doubled : kMinSndbuf;
    }
  });
  if (!receive) {
    // The frames a program has written and the bus not yet taken: its connection's own buffer.
    CANHIL_REAL(setsockopt);
    const int half = s.sndbuf / 2;
    real_setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &half, sizeof half);
  }
  return 0;
}

int give_option(void* value, socklen_t* size, const void* what, socklen_t what_size) {
  socklen_t len = 0;
  if (!copy_in(&len, size, sizeof len)) return fail(EFAULT);
  if (static_cast<int>(len) < 0) return fail(EINVAL);
  if (len > what_size) len = what_size;
  if (!copy_out(value, what, len) || !copy_out(size, &len, sizeof len)) return fail(EFAULT);
  return 0;
}

int get_raw_option(Socket& s, int name, void* value, socklen_t* size) {
  int v = 0;
  switch (name) {
    case CAN_RAW_FILTER: {
      socklen_t len = 0;
      if (!copy_in(&len, size, sizeof len)) return fail(EFAULT);
      if (static_cast<int>(len) < 0) return fail(EINVAL);
      can_filter filters[kMaxFilters];
      std::uint32_t count = 0;
      s.lock.lock();
      count = s.filter_count;
      std::memcpy(filters, s.filters, count * sizeof(can_filter));
      s.lock.unlock();
      const socklen_t need = count * sizeof(can_filter);
      if (count > 0 && len < need) {
        // raw_getsockopt: too small a buffer for the list is ERANGE, the size it needs in optlen
        copy_out(size, &need, sizeof need);
        return fail(ERANGE);
      }
      len = count > 0 ? need : 0;
      if (!copy_out(value, filters, len) || !copy_out(size, &len, sizeof len)) return fail(EFAULT);
      return 0;
    }
    case CAN_RAW_ERR_FILTER:
      v = static_cast<int>(s.err_mask);
      break;
    case CAN_RAW_LOOPBACK:
      v = (s.flags & kLoopback) != 0;
      break;
    case CAN_RAW_RECV_OWN_MSGS:
      v = (s.flags & kRecvOwn) != 0;
      break;
    case CAN_RAW_FD_FRAMES:
      v = (s.flags & kFdFrames) != 0;
      break;
    case CAN_RAW_JOIN_FILTERS:
      v = (s.flags & kJoinFilters) != 0;
      break;
    default:
      return fail(ENOPROTOOPT);
  }
  return give_option(value, size, &v, sizeof v);
}

/// 1 when `name` is not an option the bus answers itself.
int get_socket_option(Socket& s, int name, void* value, socklen_t* size) {
  int v = 0;
  switch (name) {
    case SO_TYPE:
      v = SOCK_RAW;
      break;
    case SO_DOMAIN:
      v = AF_CAN;
      break;
    case SO_PROTOCOL:
      v = 0;  // can_create leaves sk_protocol unset: the kernel answers 0
      break;
    case SO_ERROR:
      v = s.pending_error.exchange(0);
      break;
    case SO_ACCEPTCONN:
      v = 0;
      break;
    case SO_RCVBUF:
      v = s.rcvbuf > 0 ? s.rcvbuf : rmem_default();
      break;
    case SO_SNDBUF:
      v = s.sndbuf > 0 ? s.sndbuf : wmem_default();
      break;
    case SO_TIMESTAMP_OLD:
    case SO_TIMESTAMP_NEW:
      v = (s.flags & kTimestamp) != 0 && (s.flags & kTimestampNs) == 0 &&
          ((s.flags & kTimestampNew) != 0) == (name == SO_TIMESTAMP_NEW);
      break;
    case SO_TIMESTAMPNS_OLD:
    case SO_TIMESTAMPNS_NEW:
      v = (s.flags & kTimestampNs) != 0 && ((s.flags & kTimestampNew) != 0) == (name == SO_TIMESTAMPNS_NEW);
      break;
    case SO_RXQ_OVFL:
      v = (s.flags & kRxqOverflow) != 0;
      break;
    case SO_MEMINFO: {
      // sk_meminfo: what the bus knows of the socket (its buffer sizes, its
      // drops); the queue's memory is the connection's.
      std::uint32_t info[SK_MEMINFO_VARS] = {};
      info[SK_MEMINFO_RCVBUF] = static_cast<std::uint32_t>(s.rcvbuf > 0 ? s.rcvbuf : rmem_default());
      info[SK_MEMINFO_SNDBUF] = static_cast<std::uint32_t>(s.sndbuf > 0 ? s.sndbuf : wmem_default());
      info[SK_MEMINFO_DROPS] = s.drops.load(std::memory_order_relaxed);
      return give_option(value, size, info, sizeof info);
    }
    default:
      return 1;
  }
  return give_option(value, size, &v, sizeof v);
}

int stamp_ioctl(Socket& s, unsigned long request, void* arg) {
  // sock_gettstamp: from now on reads keep their frame's time; none read yet is ENOENT,
  // one read while nothing was kept is the time of this call.
  if ((s.flags & kStampKept) == 0) set_flag(s, kStampKept, true);
  std::int64_t ns = s.last_stamp_ns.load(std::memory_order_relaxed);
  if (ns < 0) return fail(ENOENT);
  if (ns == 0) {
    timespec now{};
    clock_gettime(CLOCK_REALTIME, &now);
    ns = static_cast<std::int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec;
    s.last_stamp_ns.store(ns, std::memory_order_relaxed);
  }
  if (request == SIOCGSTAMP_OLD) {
    const timeval t{ns / 1000000000, (ns % 1000000000) / 1000};
    return copy_out(arg, &t, sizeof t) ? 0 : fail(EFAULT);
  }
  if (request == SIOCGSTAMPNS_OLD) {
    const timespec t{ns / 1000000000, ns % 1000000000};
    return copy_out(arg, &t, sizeof t) ? 0 : fail(EFAULT);
  }
  const long long pair[2] = {ns / 1000000000, request == SIOCGSTAMP_NEW ? (ns % 1000000000) / 1000 : ns % 1000000000};
  return copy_out(arg, pair, sizeof pair) ? 0 : fail(EFAULT);
}

}  // namespace
}  // namespace canhil::userbus::preload

namespace bus = canhil::userbus::preload;

#pragma GCC visibility push(default)
extern "C" {

int socket(int domain, int type, int protocol) {
  CANHIL_REAL(socket);
  if (domain != PF_CAN) return real_socket(domain, type, protocol);
  if (protocol == CAN_RAW && (type & 0xf) == SOCK_RAW) {
    const int fd = bus::open_socket(type & (SOCK_NONBLOCK | SOCK_CLOEXEC));  // -2: no bus runs
    return fd != -2 ? fd : real_socket(domain, type, protocol);
  }
  if (bus::bus_state(false) == nullptr) return real_socket(domain, type, protocol);
  if (protocol == CAN_RAW) return bus::fail(EPROTOTYPE);  // can_create: the protocol's type is SOCK_RAW
  if (protocol < 0 || protocol >= CAN_NPROTO) return bus::fail(EINVAL);
  return bus::fail(EPROTONOSUPPORT);  // BCM, ISO-TP, J1939: not on the user-space bus
}

int close(int fd) {
  CANHIL_REAL(close);
  bus::mark(fd, -1);
  return real_close(fd);
}

int dup(int fd) {
  CANHIL_REAL(dup);
  const int r = real_dup(fd);
  if (r >= 0) bus::copy_mark(fd, r);
  return r;
}

int dup2(int from, int to) {
  CANHIL_REAL(dup2);
  const int r = real_dup2(from, to);
  if (r >= 0 && from != to) bus::copy_mark(from, to);
  return r;
}

int dup3(int from, int to, int flags) {
  CANHIL_REAL(dup3);
  const int r = real_dup3(from, to, flags);
  if (r >= 0) bus::copy_mark(from, to);
  return r;
}

int fcntl(int fd, int cmd, ...) {
  va_list args;
  va_start(args, cmd);
  void* arg = va_arg(args, void*);
  va_end(args);
  CANHIL_REAL(fcntl);
  const int r = real_fcntl(fd, cmd, arg);
  if (r >= 0 && (cmd == F_DUPFD || cmd == F_DUPFD_CLOEXEC)) bus::copy_mark(fd, r);
  return r;
}

int fcntl64(int fd, int cmd, ...) {
  va_list args;
  va_start(args, cmd);
  void* arg = va_arg(args, void*);
  va_end(args);
  static const auto real = canhil::preload::next_symbol<int (*)(int, int, ...)>("fcntl64");
  const int r = real != nullptr ? real(fd, cmd, arg) : static_cast<int>(syscall(SYS_fcntl, fd, cmd, arg));
  if (r >= 0 && (cmd == F_DUPFD || cmd == F_DUPFD_CLOEXEC)) bus::copy_mark(fd, r);
  return r;
}

int bind(int fd, const sockaddr* address, socklen_t size) {
  if (auto* s = bus::socket_of(fd)) return bus::bind_socket(*s, address, size);
  CANHIL_REAL(bind);
  return real_bind(fd, address, size);
}

int connect(int fd, const sockaddr* address, socklen_t size) {
  if (bus::socket_of(fd) != nullptr) return bus::fail(EOPNOTSUPP);
  CANHIL_REAL(connect);
  return real_connect(fd, address, size);
}

int listen(int fd, int backlog) {
  if (bus::socket_of(fd) != nullptr) return bus::fail(EOPNOTSUPP);
  CANHIL_REAL(listen);
  return real_listen(fd, backlog);
}

int shutdown(int fd, int how) {
  if (bus::socket_of(fd) != nullptr) return bus::fail(EOPNOTSUPP);
  CANHIL_REAL(shutdown);
  return real_shutdown(fd, how);
}

int getsockname(int fd, sockaddr* address, socklen_t* size) {
  if (auto* s = bus::socket_of(fd)) {
    sockaddr_can a{};
    a.can_family = AF_CAN;
    a.can_ifindex = s->ifindex;
    socklen_t len = 0;
    if (!bus::copy_in(&len, size, sizeof len)) return bus::fail(EFAULT);
    if (static_cast<int>(len) < 0) return bus::fail(EINVAL);
    const socklen_t give = len < bus::kMinName ? len : bus::kMinName;
    const socklen_t full = bus::kMinName;
    if (!bus::copy_out(address, &a, give) || !bus::copy_out(size, &full, sizeof full)) return bus::fail(EFAULT);
    return 0;
  }
  CANHIL_REAL(getsockname);
  return real_getsockname(fd, address, size);
}

int getpeername(int fd, sockaddr* address, socklen_t* size) {
  if (bus::socket_of(fd) != nullptr) return bus::fail(EOPNOTSUPP);
  CANHIL_REAL(getpeername);
  return real_getpeername(fd, address, size);
}

int setsockopt(int fd, int level, int name, const void* value, socklen_t size) {
  if (auto* s = bus::socket_of(fd)) {
    if (level == SOL_CAN_RAW) return bus::set_raw_option(*s, name, value, size);
    if (level == SOL_SOCKET) {
      const int r = bus::set_socket_option(fd, *s, name, value, size);
      if (r != 1) return r;
    } else {
      return bus::fail(EINVAL);  // raw_setsockopt: a level not its own
    }
  }
  CANHIL_REAL(setsockopt);
  return real_setsockopt(fd, level, name, value, size);
}

int getsockopt(int fd, int level, int name, void* value, socklen_t* size) {
  if (auto* s = bus::socket_of(fd)) {
    if (level == SOL_CAN_RAW) return bus::get_raw_option(*s, name, value, size);
    if (level == SOL_SOCKET) {
      const int r = bus::get_socket_option(*s, name, value, size);
      if (r != 1) return r;
    } else {
      return bus::fail(EINVAL);
    }
  }
  CANHIL_REAL(getsockopt);
  return real_getsockopt(fd, level, name, value, size);
}

int ioctl(int fd, unsigned long request, ...) {
  va_list args;
  va_start(args, request);
  void* arg = va_arg(args, void*);
  va_end(args);
  if (auto* s = bus::socket_of(fd)) {
    switch (request) {
      case SIOCGSTAMP_OLD:
      case SIOCGSTAMPNS_OLD:
      case SIOCGSTAMP_NEW:
      case SIOCGSTAMPNS_NEW:
        return bus::stamp_ioctl(*s, request, arg);
      case FIONREAD:
      case SIOCOUTQ:
        return bus::fail(ENOTTY);  // raw.c has no ioctls of its own
      default:
        break;
    }
  }
  if (bus::bus_state(false) != nullptr) {
    const int r = bus::interface_ioctl(request, arg);
    if (r != 1) return r;
  }
  CANHIL_REAL(ioctl);
  return real_ioctl(fd, request, arg);
}

}  // extern "C"
#pragma GCC visibility pop
