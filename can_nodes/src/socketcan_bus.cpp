#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/base/errno_text.hpp"
#include "canhil/can_nodes/medium.hpp"
#include "canhil/userbus/bus_hook.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/sock_diag.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>

#include <vector>

namespace canhil::can_nodes {
namespace {

can_frame to_kernel(const CanFrame& f) {
  can_frame k{};
  switch (f.kind) {
    case frames::FrameKind::kError:
      k.can_id = (f.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
      break;
    case frames::FrameKind::kRemote:
      k.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
      k.can_id |= CAN_RTR_FLAG;
      break;
    case frames::FrameKind::kData:
      k.can_id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
      break;
  }
  k.len = f.len > CAN_MAX_DLEN ? CAN_MAX_DLEN : f.len;
  k.len8_dlc = f.len8_dlc;
  std::memcpy(k.data, f.data.data(), CAN_MAX_DLEN);
  return k;
}

CanFrame from_kernel(const can_frame& k) {
  CanFrame f;
  if ((k.can_id & CAN_ERR_FLAG) != 0u) {
    f.kind = frames::FrameKind::kError;
    f.id = k.can_id & CAN_ERR_MASK;
  } else {
    f.extended = (k.can_id & CAN_EFF_FLAG) != 0u;
    f.id = k.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
    if ((k.can_id & CAN_RTR_FLAG) != 0u) f.kind = frames::FrameKind::kRemote;
  }
  f.len = k.len > CAN_MAX_DLEN ? static_cast<std::uint8_t>(CAN_MAX_DLEN) : k.len;
  f.len8_dlc = k.len8_dlc;
  if (f.kind != frames::FrameKind::kRemote) std::memcpy(f.data.data(), k.data, f.len);
  return f;
}

int open_raw_socket() { return ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW); }

}  // namespace

bool kernel_has_can() {
  const int fd = open_raw_socket();
  if (fd < 0) return false;
  ::close(fd);
  return true;
}

bool on_user_space_bus(const std::string& iface) { return socketcan_medium_kind(iface) == MediumKind::kUserSpace; }

const char* bus_of(const std::string& iface) { return medium_name(socketcan_medium_kind(iface)); }

std::unique_ptr<SocketCanBus> SocketCanBus::open(const std::string& iface, const SocketCanOptions& options) {
  if (iface.empty() || iface.size() >= IFNAMSIZ) {
    throw SetupError("\"" + iface + "\" is not a valid interface name (1 to " + std::to_string(IFNAMSIZ - 1) +
                     " characters)");
  }
  const int fd = open_raw_socket();
  if (fd < 0) {
    const int err = errno;
    throw SetupError("cannot open a CAN socket (" + errno_text(err) +
                     "): this kernel has no SocketCAN. Load the modules (modprobe can-raw vcan) or, where the "
                     "kernel has no CAN at all, run inside the VM runner: vcan_setup/vm-run.sh -- COMMAND");
  }
  const unsigned ifindex = if_nametoindex(iface.c_str());
  if (ifindex == 0) {
    ::close(fd);
    throw SetupError("no network interface named " + iface + ": create it with `vcan_setup/vcan-up.sh " + iface +
                     "` (virtual CAN) or bring up a real one with `ip link set " + iface +
                     " up type can bitrate 1000000`");
  }
  auto fail = [&](const char* what) {
    const int err = errno;
    ::close(fd);
    throw SetupError("cannot set up CAN socket on " + iface + ": " + what + ": " + errno_text(err));
  };
  const int one = 1;
  if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) < 0) fail("SO_TIMESTAMPNS");
  if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) < 0) fail("SO_RXQ_OVFL");
  if (options.receive_own) {
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &one, sizeof one) < 0) fail("CAN_RAW_RECV_OWN_MSGS");
  }
  if (options.receive_buffer_bytes > 0) {
    // SO_RCVBUFFORCE (root) ignores rmem_max; fall back to SO_RCVBUF.
    if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &options.receive_buffer_bytes, sizeof(int)) < 0 &&
        ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &options.receive_buffer_bytes, sizeof(int)) < 0) {
      fail("SO_RCVBUF");
    }
  }
  const can_err_mask_t no_errors = 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &no_errors, sizeof no_errors) < 0) fail("CAN_RAW_ERR_FILTER");
  auto bus = std::unique_ptr<SocketCanBus>(new SocketCanBus(fd, iface, static_cast<int>(ifindex), options));
  if (options.fed) {
    // The kernel queues nothing here: feed() gives what the filters pass.
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, nullptr, 0) < 0) fail("CAN_RAW_FILTER");
  }
  if (!options.filters.empty()) bus->set_filters(options.filters);  // before bind: nothing else gets in
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    const int err = errno;
    throw SetupError("cannot set up CAN socket on " + iface + ": bind: " + errno_text(err));  // ~SocketCanBus closes fd
  }
  bus->refresh_state();
  bus->stats_.state_changes = 0;
  return bus;
}

SocketCanBus::SocketCanBus(int fd, std::string iface, int ifindex, const SocketCanOptions& options)
    : fd_(fd), iface_(std::move(iface)), ifindex_(ifindex), options_(options) {
  // The bus's preload, in this process when it runs on the bus (canhil does not link it).
  if (on_user_space_bus(iface_)) waiting_ = userbus::hooks().waiting;
}

std::optional<bool> SocketCanBus::waiting() const {
  if (waiting_ == nullptr) return std::nullopt;
  const long long n = waiting_(fd_);
  if (n < 0) return std::nullopt;
  return n > 0;
}

SocketCanBus::~SocketCanBus() { ::close(fd_); }

void SocketCanBus::note_errno(int err) {
  BusState s = state_;
  if (err == ENETDOWN) s = BusState::kDown;
  if (err == ENODEV || err == ENXIO) s = BusState::kGone;
  if (s != state_) {
    state_ = s;
    ++stats_.state_changes;
  }
}

SendStatus SocketCanBus::send(const CanFrame& frame) {
  const can_frame k = to_kernel(frame);
  for (int attempt = 0;; ++attempt) {
    const ssize_t n = ::write(fd_, &k, sizeof k);
    if (n == static_cast<ssize_t>(sizeof k)) {
      ++stats_.sent;
      if (options_.fed) {
        // Fed back in bus order; a frame lost on its way (kept for ever here)
        // would stop nothing: the oldest goes once many wait.
        if (own_.size() >= kMostOwnInFlight) own_.pop_front();
        own_.push_back(from_kernel(k));  // as the driver's socket will read it
      }
      if (state_ != BusState::kUp) {
        state_ = BusState::kUp;
        ++stats_.state_changes;
      }
      return SendStatus::kOk;
    }
    const int err = n < 0 ? errno : EIO;
    if ((err == ENOBUFS || err == EAGAIN) && attempt < options_.send_retries) {
      ++stats_.send_retries;
      // Wait for room in the queue; ENOBUFS is not always signalled by POLLOUT,
      // so the bounded timeout doubles as a short back-off.
      pollfd p{fd_, POLLOUT, 0};
      const auto us = options_.retry_wait.count();
      const timespec wait{static_cast<time_t>(us / 1'000'000), static_cast<long>((us % 1'000'000) * 1000)};
      ::ppoll(&p, 1, &wait, nullptr);
      continue;
    }
    if (err == EINTR) continue;
    note_errno(err);
    if (state_ != BusState::kUp) return SendStatus::kDown;
    ++stats_.send_dropped;
    return SendStatus::kDropped;
  }
}

std::optional<TimedFrame> SocketCanBus::receive() {
  if (options_.fed) return take_fed();
  if (options_.skips_empty_reads && waiting() == false) {
    ++skipped_;
    found_empty();
    return std::nullopt;
  }
  can_frame k{};
  iovec iov{&k, sizeof k};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  ssize_t n = 0;
  do {
    n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  } while (n < 0 && errno == EINTR);
  if (n < 0) {
    const int err = errno;
    if (err != EAGAIN && err != EWOULDBLOCK) note_errno(err);
    found_empty();
    return std::nullopt;
  }
  read_since_drop_check_ = true;
  if (n != static_cast<ssize_t>(sizeof k)) return std::nullopt;  // CAN FD on this socket is not enabled
  TimedFrame out{from_kernel(k), Nanos{0}};
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SO_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      out.time = std::chrono::seconds(ts.tv_sec) + Nanos(ts.tv_nsec);
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t drops = 0;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      note_drops(drops);
    }
  }
  if (options_.clock != nullptr) out.time = options_.clock->now();
  count_received(out.frame);
  if (state_ != BusState::kUp) {
    state_ = BusState::kUp;
    ++stats_.state_changes;
  }
  return out;
}

void SocketCanBus::found_empty() {
  // Drops after the last received frame are reported with no later frame's
  // SO_RXQ_OVFL, so read the socket's drop counter directly. Only a full
  // queue drops, so an empty queue that stayed empty has none new.
  if (read_since_drop_check_ && options_.drops_when_empty) {
    read_drop_counter();
    read_since_drop_check_ = false;
  }
}

void SocketCanBus::note_drops(std::uint32_t absolute) const {
  // The kernel's per-socket drop counter (sk_drops) only grows, modulo 2^32.
  // A frame's SO_RXQ_OVFL is the count when it was queued: one queued before
  // drops that SO_MEMINFO has already told carries an older count, which
  // adds nothing (read as new, it would add 2^32 less what it lags by).
  const auto ahead = static_cast<std::int32_t>(absolute - last_drop_count_);
  if (ahead <= 0) return;
  stats_.rx_overflow += static_cast<std::uint32_t>(ahead);
  last_drop_count_ = absolute;
}

void SocketCanBus::read_drop_counter() const {
  std::uint32_t info[SK_MEMINFO_VARS] = {};
  socklen_t len = sizeof info;
  if (::getsockopt(fd_, SOL_SOCKET, SO_MEMINFO, info, &len) == 0 && len > SK_MEMINFO_DROPS * sizeof(std::uint32_t)) {
    note_drops(info[SK_MEMINFO_DROPS]);
  }
}

BusStats SocketCanBus::stats() const {
  read_drop_counter();
  return stats_;
}

void SocketCanBus::feed(const CanFrame& frame) {
  if (!own_.empty() && own_.front() == frame) {
    own_.pop_front();  // its own: the kernel would not give it back
    return;
  }
  bool passes = false;
  if (frame.kind == frames::FrameKind::kError) {
    passes = (frame.id & error_mask_) != 0;
  } else if (filters_.empty()) {
    passes = !filters_set_empty_;
  } else {
    passes = std::any_of(filters_.begin(), filters_.end(), [&frame](const Filter& f) { return f.matches(frame); });
  }
  if (passes) fed_.push_back(frame);
}

std::optional<TimedFrame> SocketCanBus::take_fed() {
  if (fed_.empty()) return std::nullopt;
  TimedFrame out{fed_.front(), options_.clock != nullptr ? options_.clock->now() : Nanos{0}};
  fed_.pop_front();
  count_received(out.frame);
  return out;
}

void SocketCanBus::count_received(const CanFrame& frame) {
  ++(frame.kind == frames::FrameKind::kError ? stats_.errors : stats_.received);
}

void SocketCanBus::set_filters(std::span<const Filter> filters) {
  std::vector<can_filter> k;
  k.reserve(filters.size());
  for (const Filter& f : filters) {
    can_filter c{};
    c.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0u) | (f.remote ? CAN_RTR_FLAG : 0u);
    if (f.invert) c.can_id |= CAN_INV_FILTER;
    c.can_mask = f.mask | (f.match_extended ? CAN_EFF_FLAG : 0u) | (f.match_remote ? CAN_RTR_FLAG : 0u);
    k.push_back(c);
  }
  if (!options_.fed && ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, k.empty() ? nullptr : k.data(),
                                    static_cast<socklen_t>(k.size() * sizeof(can_filter))) < 0) {
    const int err = errno;
    throw SetupError("cannot set " + std::to_string(k.size()) + " receive filters on " + iface_ + ": " +
                     errno_text(err) + " (the kernel limits the count to CAN_RAW_FILTER_MAX, 512)");
  }
  filters_.assign(filters.begin(), filters.end());
  filters_set_empty_ = filters.empty();  // no filter at all: the socket hears nothing
}

void SocketCanBus::set_error_mask(std::uint32_t mask) {
  const can_err_mask_t m = mask & CAN_ERR_MASK;
  if (!options_.fed && ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &m, sizeof m) < 0) {
    const int err = errno;
    throw SetupError("cannot set the error-frame mask on " + iface_ + ": " + errno_text(err));
  }
  error_mask_ = m;
}

bool SocketCanBus::wait_readable(std::chrono::microseconds timeout) const {
  pollfd p{fd_, POLLIN, 0};
  const auto us = timeout.count();
  const timespec wait{static_cast<time_t>(us / 1'000'000), static_cast<long>((us % 1'000'000) * 1000)};
  return ::ppoll(&p, 1, &wait, nullptr) > 0 && (p.revents & POLLIN) != 0;
}

BusState SocketCanBus::refresh_state() {
  ifreq req{};
  std::strncpy(req.ifr_name, iface_.c_str(), IFNAMSIZ - 1);
  // Gone: no such interface any more, or removed and created again (this
  // socket stays bound to the old index).
  const bool gone =
      ::ioctl(fd_, SIOCGIFFLAGS, &req) < 0 || if_nametoindex(iface_.c_str()) != static_cast<unsigned>(ifindex_);
  BusState s = BusState::kUp;
  if (gone) {
    s = BusState::kGone;
  } else if ((req.ifr_flags & IFF_UP) == 0 || (req.ifr_flags & IFF_RUNNING) == 0) {
    s = BusState::kDown;
  }
  if (s != state_) {
    state_ = s;
    ++stats_.state_changes;
  }
  return state_;
}

}  // namespace canhil::can_nodes
