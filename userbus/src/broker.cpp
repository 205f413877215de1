// The broker: one process per bus that routes every frame a socket sends to
// every socket whose binding and filters want it, with the kernel's CAN_RAW
// rules (net/can/af_can.c's filter lists, net/can/raw.c's loopback, own
// messages and joined filters). One thread, one epoll; each socket a
// SOCK_SEQPACKET connection.
#include <linux/can/error.h>
#include <poll.h>
#include <sched.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

#include "broker_system.hpp"
#include "canhil/base/preload.hpp"
#include "canhil/base/process.hpp"
#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {
namespace {

/// A filter as the kernel registers it (af_can.c, can_rcv_list_find): the
/// mask reduced, the id masked, and its list (error, inverted or plain).
struct Registered {
  canid_t id;
  canid_t mask;
  bool error;
  bool inverted;
};

Registered register_filter(canid_t id, canid_t mask) {
  const bool inverted = (id & CAN_INV_FILTER) != 0;
  if ((mask & CAN_ERR_FLAG) != 0) return {id, mask & CAN_ERR_MASK, true, false};
  if ((mask & CAN_EFF_FLAG) != 0 && (id & CAN_EFF_FLAG) == 0) mask &= (CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG);
  return {id & mask, mask, false, inverted};
}

bool matches(const Registered& r, canid_t can_id) {
  if ((can_id & CAN_ERR_FLAG) != 0) return r.error && (can_id & r.mask) != 0;
  if (r.error) return false;
  const bool equal = (can_id & r.mask) == r.id;
  return r.inverted ? !equal : equal;
}

/// What the broker keeps of a socket's options, refreshed when its seq moves.
struct Options {
  std::uint32_t seq = ~0U;
  std::int32_t ifindex = 0;
  bool bound = false;
  std::uint32_t flags = 0;
  std::int32_t rcvbuf = 0;
  std::uint32_t count = 0;          // the user's filters (joined filters must all match)
  bool single_ids = false;          // every filter takes one standard or extended id (the kernel serves those last)
  std::vector<Registered> filters;  // the user's, then the error filter if any
  // single_ids: the filters' ids, sorted, standard and extended apart (a
  // delivery fence's 512 filters a socket are a search, not 512 tests a frame).
  std::vector<canid_t> standard_ids;
  std::vector<canid_t> extended_ids;
};

struct Connection {
  int fd = -1;
  int slot = -1;  // -1 until its hello, and for a control connection
  bool control = false;
  bool hello = false;
  bool overrun = false;  // its buffer was full past the grace: drop at once until it reads
  std::int32_t applied_rcvbuf = 0;
  Options options;
  std::vector<RxRecord> queued;  // routed in this round, sent together at its end
  std::uint64_t opened = 0;      // the order connections were opened in
};

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

// Past the time shim: a broker started by a process with the shim preloaded
// must not read a virtual clock that stands still.
std::int64_t monotonic_ns() {
  const timespec t = ::canhil::preload::real_monotonic();
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

class Broker {
 public:
  Broker(int listen_fd, State& state, const BrokerOptions& options)
      : listen_fd_(listen_fd), state_(state), options_(options) {
    epoll_ = epoll_create1(EPOLL_CLOEXEC);
    watch(listen_fd_);
    if (options_.owner > 0) {
      owner_fd_ = static_cast<int>(syscall(SYS_pidfd_open, options_.owner, 0));
      if (owner_fd_ >= 0) watch(owner_fd_);
    }
    for (int k = 0; k < kMaxInterfaces; ++k)
      up_[k] = state_.interfaces[k].up.load() != 0 && state_.interfaces[k].in_use.load() != 0;
  }

  ~Broker() {
    for (Connection& c : connections_) {
      if (c.fd >= 0) close(c.fd);
    }
    if (owner_fd_ >= 0) close(owner_fd_);
    if (asker_fd_ >= 0) close(asker_fd_);
    close(epoll_);
  }
  Broker(const Broker&) = delete;
  Broker& operator=(const Broker&) = delete;

  void run() {
    epoll_event events[64];
    // Where the kernel gives no pidfd (before Linux 5.3, or a seccomp
    // profile refusing it), the owner is looked for twice a second instead.
    const bool look_for_owner = options_.owner > 0 && owner_fd_ < 0;
    while (!stop_) {
      int n = spin(events);
      if (n == 0) n = epoll_wait(epoll_, events, 64, look_for_owner ? 500 : -1);
      const int wait_error = errno;
      if (look_for_owner && !process_alive(options_.owner)) return;
      if (n < 0) {
        if (wait_error == EINTR) continue;
        return;
      }
      for (int i = 0; i < n && !stop_; ++i) {
        const int fd = events[i].data.fd;
        if (fd == listen_fd_) {
          accept_all();
        } else if (fd == owner_fd_) {
          stop_ = true;
        } else {
          serve(fd, events[i].events);
        }
      }
    }
  }

 private:
  // What arrives within the spin a lockstep run asked for (State::spin),
  // looked for while giving way to any other runnable thread: 0 when nothing
  // came, or when no living run asks.
  int spin(epoll_event* events) {
    const std::uint64_t word = state_.spin.load(std::memory_order_acquire);
    const std::uint32_t us = spin_us(word);
    const bool asked = us != 0 && asker_alive(spin_pid(word));
    // At SCHED_FIFO, sched_yield gives way to no normal process: the broker
    // looks on at the normal scheduler, and is real-time again once no run asks.
    if (state_.rt_priority > 0 && asked == fifo_) {
      fifo_ = !asked;
      set_fifo(fifo_, state_.rt_priority);
    }
    if (!asked) return 0;
    state_.spins.fetch_add(1, std::memory_order_relaxed);
    const std::int64_t until = monotonic_ns() + static_cast<std::int64_t>(us) * 1000;
    for (;;) {
      const int n = epoll_wait(epoll_, events, 64, 0);
      if (n != 0 || monotonic_ns() >= until) return n;
      sched_yield();
    }
  }

  // Whether the process that asked for the spin still runs: through a pidfd,
  // which says so once it has ended even before it is reaped, and cannot be
  // taken for a later process of the same pid; else by kill(pid, 0).
  bool asker_alive(pid_t pid) {
    if (pid != asker_pid_) {
      if (asker_fd_ >= 0) close(asker_fd_);
      asker_pid_ = pid;
      asker_fd_ = pid > 0 ? static_cast<int>(syscall(SYS_pidfd_open, pid, 0)) : -1;
      asker_gone_ = pid <= 0 || (asker_fd_ < 0 && errno == ESRCH);
    }
    if (asker_gone_) return false;
    if (asker_fd_ < 0) return process_alive(pid);
    pollfd p{asker_fd_, POLLIN, 0};
    const timespec at_once{0, 0};
    asker_gone_ = syscall(SYS_ppoll, &p, 1, &at_once, nullptr, 8) != 0;  // readable once it has ended
    return !asker_gone_;
  }

  void watch(int fd) {
    epoll_event e{};
    e.events = EPOLLIN;
    e.data.fd = fd;
    epoll_ctl(epoll_, EPOLL_CTL_ADD, fd, &e);
  }

  Connection& connection(int fd) {
    if (static_cast<std::size_t>(fd) >= connections_.size()) connections_.resize(static_cast<std::size_t>(fd) + 1);
    return connections_[static_cast<std::size_t>(fd)];
  }

  void accept_all() {
    for (;;) {
      const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;
      ucred peer{};
      socklen_t len = sizeof peer;
      if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &peer, &len) != 0 || peer.uid != getuid()) {
        close(fd);  // another user's process: the bus is its creator's only
        continue;
      }
      Connection& c = connection(fd);
      c = Connection{};
      c.fd = fd;
      c.opened = ++opened_;
      watch(fd);
    }
  }

  void drop(Connection& c) {
    epoll_ctl(epoll_, EPOLL_CTL_DEL, c.fd, nullptr);
    close(c.fd);
    if (c.slot >= 0) {
      Socket& s = state_.sockets[c.slot];
      s.in_use.store(0, std::memory_order_release);
    }
    c = Connection{};
  }

  void serve(int fd, std::uint32_t events) {
    Connection& c = connection(fd);
    if (c.fd < 0) return;
    if (!c.hello) {
      hello(c);
      return;
    }
    if (c.control) {
      control(c);
      return;
    }
    // Up to a batch of frames in one call, then the other connections get their turn.
    constexpr unsigned kBatch = 64;
    mmsghdr in[kBatch] = {};
    iovec parts[kBatch];
    for (unsigned k = 0; k < kBatch; ++k) {
      parts[k] = {&batch_[k], sizeof(TxRecord)};
      in[k].msg_hdr.msg_iov = &parts[k];
      in[k].msg_hdr.msg_iovlen = 1;
    }
    const int n = recvmmsg(c.fd, in, kBatch, MSG_DONTWAIT, nullptr);
    if (n < 0) {
      if (errno != EAGAIN && errno != EINTR) drop(c);
      return;
    }
    bool ended = n == 0;
    for (int k = 0; k < n; ++k) {
      const TxRecord& record = batch_[k];
      if (in[k].msg_len == 0) {  // the program closed its socket
        ended = true;
        break;
      }
      if (in[k].msg_len == kTxHeader + record.size && (record.size == CAN_MTU || record.size == CANFD_MTU) &&
          record.frame[offsetof(can_frame, len)] <= (record.size == CAN_MTU ? CAN_MAX_DLEN : CANFD_MAX_DLEN)) {
        route(c, record);
      }
    }
    flush();
    if (ended) drop(c);
    (void)events;  // a hang-up is read as the end of the connection, once its frames are routed
  }

  void hello(Connection& c) {
    Hello h{};
    const ssize_t n = recv(c.fd, &h, sizeof h, MSG_DONTWAIT);
    if (n != static_cast<ssize_t>(sizeof h)) {
      if (n < 0 && errno == EAGAIN) return;
      drop(c);
      return;
    }
    c.hello = true;
    if (h.kind == kHelloControl) {
      c.control = true;
      return;
    }
    Welcome w{-ENOBUFS};
    for (int k = 0; k < kMaxSockets; ++k) {
      Socket& s = state_.sockets[k];
      if (s.in_use.load(std::memory_order_acquire) != 0) continue;
      s.lock.lock();
      s.pid = h.pid;
      s.ifindex = 0;
      s.bound = 0;
      s.flags = kLoopback;
      s.err_mask = 0;
      s.rcvbuf = 0;
      s.sndbuf = 0;
      s.filter_count = 1;  // raw_init: one filter that takes every frame
      s.filters[0] = can_filter{0, 0};
      sockaddr_un peer{};
      socklen_t len = sizeof peer;
      std::memset(s.peer, 0, sizeof s.peer);
      if (getpeername(c.fd, reinterpret_cast<sockaddr*>(&peer), &len) == 0 && len > sizeof(sa_family_t)) {
        std::memcpy(s.peer, peer.sun_path, std::min<std::size_t>(len - sizeof(sa_family_t), sizeof s.peer));
      }
      s.pending_error.store(0);
      s.last_stamp_ns.store(-1);
      s.drops.store(0);
      s.received.store(0);
      s.sent.store(0);
      s.taken.store(0);
      s.seq.fetch_add(2, std::memory_order_release);
      s.lock.unlock();
      s.in_use.store(1, std::memory_order_release);
      c.slot = k;
      w.slot = k;
      break;
    }
    if (send(c.fd, &w, sizeof w, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof w) || w.slot < 0) drop(c);
  }

  void control(Connection& c) {
    ControlRequest r{};
    const ssize_t n = recv(c.fd, &r, sizeof r, MSG_DONTWAIT);
    if (n < 0 && errno == EAGAIN) return;
    int answer = -EINVAL;
    if (n == static_cast<ssize_t>(sizeof r)) {
      if (r.op == kControlInterfacesChanged) {
        interfaces_changed();
        answer = 0;
      } else if (r.op == kControlStop) {
        stop_ = true;
        answer = 0;
      }
    }
    if (n > 0) send(c.fd, &answer, sizeof answer, MSG_NOSIGNAL | MSG_DONTWAIT);
    drop(c);
  }

  /// An interface went down or away: every socket bound to it is told, as
  /// raw.c's notifier tells it (ENETDOWN; ENODEV and unbound when removed).
  void interfaces_changed() {
    for (int k = 0; k < kMaxInterfaces; ++k) {
      const Interface& i = state_.interfaces[k];
      const bool exists = i.in_use.load() != 0;
      const bool up = exists && i.up.load() != 0;
      const bool removed = !exists && known_[k];
      const bool went_down = exists && !up && up_[k];
      known_[k] = exists;
      up_[k] = up;
      if (!removed && !went_down) continue;
      const int index = kFirstIndex + k;
      for (Connection& c : connections_) {
        if (c.fd < 0 || c.slot < 0) continue;
        Socket& s = state_.sockets[c.slot];
        if (s.bound == 0 || s.ifindex != index) continue;
        if (removed) {
          s.lock.lock();
          s.seq.fetch_add(1, std::memory_order_release);
          s.ifindex = 0;
          s.bound = 0;
          s.filter_count = 0;
          s.seq.fetch_add(1, std::memory_order_release);
          s.lock.unlock();
        }
        RxRecord r{};
        r.error = removed ? ENODEV : ENETDOWN;
        if (send(c.fd, &r, kRxHeader, MSG_DONTWAIT | MSG_NOSIGNAL) > 0)
          s.received.fetch_add(1, std::memory_order_release);
      }
    }
  }

 public:
  void note_interfaces() {
    for (int k = 0; k < kMaxInterfaces; ++k) known_[k] = state_.interfaces[k].in_use.load() != 0;
  }

 private:
  /// c's options as the processes last wrote them (a seqlock read).
  const Options& options(Connection& c) {
    Socket& s = state_.sockets[c.slot];
    const std::uint32_t seq = s.seq.load(std::memory_order_acquire);
    if (seq == c.options.seq) return c.options;
    for (;;) {
      const std::uint32_t before = s.seq.load(std::memory_order_acquire);
      if ((before & 1U) != 0) continue;
      Options o;
      o.seq = before;
      o.ifindex = s.ifindex;
      o.bound = s.bound != 0;
      o.flags = s.flags;
      o.rcvbuf = s.rcvbuf;
      o.count = std::min<std::uint32_t>(s.filter_count, kMaxFilters);
      o.filters.reserve(o.count + 1);
      for (std::uint32_t f = 0; f < o.count; ++f)
        o.filters.push_back(register_filter(s.filters[f].can_id, s.filters[f].can_mask));
      o.single_ids = o.count > 0;
      for (std::uint32_t f = 0; f < o.count; ++f) {
        const canid_t id = s.filters[f].can_id;
        const canid_t mask = s.filters[f].can_mask;
        const canid_t flags = CAN_EFF_FLAG | CAN_RTR_FLAG;
        const bool one =
            (id & (CAN_INV_FILTER | CAN_RTR_FLAG)) == 0 &&
            (mask == (CAN_SFF_MASK | flags) || ((id & CAN_EFF_FLAG) != 0 && mask == (CAN_EFF_MASK | flags)));
        o.single_ids = o.single_ids && one;
      }
      if (o.single_ids) {
        for (const Registered& r : o.filters)
          ((r.id & CAN_EFF_FLAG) != 0 ? o.extended_ids : o.standard_ids).push_back(r.id);
        std::sort(o.standard_ids.begin(), o.standard_ids.end());
        std::sort(o.extended_ids.begin(), o.extended_ids.end());
      }
      if ((s.err_mask & CAN_ERR_MASK) != 0)
        o.filters.push_back(register_filter(0, (s.err_mask & CAN_ERR_MASK) | CAN_ERR_FLAG));
      std::atomic_thread_fence(std::memory_order_acquire);
      if (s.seq.load(std::memory_order_relaxed) != before) continue;
      c.options = std::move(o);
      break;
    }
    if (c.options.rcvbuf != c.applied_rcvbuf && c.options.rcvbuf > 0) {
      // What the program asked of its receive buffer is the broker's send buffer towards it.
      const int size = c.options.rcvbuf / 2;
      setsockopt(c.fd, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
      c.applied_rcvbuf = c.options.rcvbuf;
    }
    return c.options;
  }

  /// Whether socket options `o` take a frame of `can_id` (raw_rcv's rules:
  /// any filter, or every filter when they are joined).
  static bool wants(const Options& o, canid_t can_id) {
    const bool joined = (o.flags & kJoinFilters) != 0 && o.count > 1;
    if (!joined && o.single_ids && (can_id & CAN_ERR_FLAG) == 0) {
      // A single-id filter's mask keeps the id, the EFF and the RTR flags (11
      // bits of the id for a standard one, 29 for an extended one).
      constexpr canid_t kFlags = CAN_EFF_FLAG | CAN_RTR_FLAG;
      return std::binary_search(o.standard_ids.begin(), o.standard_ids.end(), can_id & (CAN_SFF_MASK | kFlags)) ||
             std::binary_search(o.extended_ids.begin(), o.extended_ids.end(), can_id & (CAN_EFF_MASK | kFlags));
    }
    std::uint32_t hits = 0;
    for (const Registered& r : o.filters) {
      if (!matches(r, can_id)) continue;
      if (!joined) return true;
      ++hits;
    }
    return hits > 0 && hits >= o.count;
  }

  void route(Connection& sender, const TxRecord& record) {
    Interface* iface = find_interface(state_, record.ifindex);
    if (iface == nullptr || iface->up.load(std::memory_order_relaxed) == 0) return;
    iface->frames.fetch_add(1, std::memory_order_relaxed);
    state_.sockets[sender.slot].sent.fetch_add(1, std::memory_order_relaxed);
    // A virtual interface has no wire: with loopback off nobody hears the frame.
    if ((options(sender).flags & kLoopback) == 0) return;
    canid_t can_id = 0;
    std::memcpy(&can_id, record.frame, sizeof can_id);
    RxRecord out{};
    out.stamp_ns = now_ns();
    out.ifindex = record.ifindex;
    out.size = record.size;
    std::memcpy(out.frame, record.frame, record.size);
    for (Connection& c : connections_) {
      if (c.fd < 0 || c.slot < 0) continue;
      const Options& o = options(c);
      if (!o.bound || (o.ifindex != 0 && o.ifindex != record.ifindex)) continue;
      const bool own = &c == &sender;
      if (own && (o.flags & kRecvOwn) == 0) continue;
      if (record.size != CAN_MTU && (o.flags & kFdFrames) == 0) continue;
      if (!wants(o, can_id)) continue;
      out.msg_flags = static_cast<std::uint32_t>(MSG_DONTROUTE) | (own ? static_cast<std::uint32_t>(MSG_CONFIRM) : 0U);
      deliver(c, out);
    }
  }

  /// Queues `r` for `c`, with the count of c's drops so far (SO_RXQ_OVFL).
  void deliver(Connection& c, RxRecord& r) {
    r.drops = state_.sockets[c.slot].drops.load(std::memory_order_relaxed);
    if (c.queued.empty()) dirty_.push_back(c.fd);
    c.queued.push_back(r);
  }

  /// One round: what route() queued handed to its sockets, State::rounds odd
  /// meanwhile.
  void flush() {
    if (dirty_.empty()) return;
    state_.rounds.fetch_add(1, std::memory_order_acq_rel);
    hand_over();
    state_.rounds.fetch_add(1, std::memory_order_release);
  }

  /// Sends every connection what this round routed to it, in one call each;
  /// a receiver whose buffer is full gets the grace once, then drops.
  void hand_over() {
    // In the kernel's order of serving (af_can.c, can_rcv_filter): sockets
    // with no filter, mask or inverted filters first, those whose filters all
    // take a single id last; within each, the latest opened first. A socket
    // served last (canhil's delivery fence) that has a frame tells that every
    // socket has it, on this bus as on a vcan.
    std::sort(dirty_.begin(), dirty_.end(), [this](int a, int b) {
      const Connection& x = connections_[static_cast<std::size_t>(a)];
      const Connection& y = connections_[static_cast<std::size_t>(b)];
      if (x.options.single_ids != y.options.single_ids) return !x.options.single_ids;
      return x.opened > y.opened;
    });
    for (const int fd : dirty_) {
      Connection& c = connections_[static_cast<std::size_t>(fd)];
      if (c.fd < 0 || c.slot < 0) continue;
      Socket& s = state_.sockets[c.slot];
      std::size_t done = 0;
      while (done < c.queued.size()) {
        const std::size_t count = std::min<std::size_t>(c.queued.size() - done, 64);
        mmsghdr out[64] = {};
        iovec parts[64];
        for (std::size_t k = 0; k < count; ++k) {
          RxRecord& r = c.queued[done + k];
          parts[k] = {&r, kRxHeader + r.size};
          out[k].msg_hdr.msg_iov = &parts[k];
          out[k].msg_hdr.msg_iovlen = 1;
        }
        const int sent = sendmmsg(c.fd, out, static_cast<unsigned>(count), MSG_DONTWAIT | MSG_NOSIGNAL);
        if (sent > 0) {
          done += static_cast<std::size_t>(sent);
          c.overrun = false;
          s.received.fetch_add(static_cast<std::uint64_t>(sent), std::memory_order_release);
          continue;
        }
        if (sent < 0 && errno != EAGAIN) break;  // the program is going: its end is read next
        if (!c.overrun && room_came(c.fd, s.pid, s.taken, options_.grace_us, options_.patience_us)) continue;
        c.overrun = true;
        const auto lost = static_cast<std::uint32_t>(c.queued.size() - done);
        s.drops.fetch_add(lost, std::memory_order_relaxed);
        if (Interface* i = find_interface(state_, c.queued[done].ifindex))
          i->dropped.fetch_add(lost, std::memory_order_relaxed);
        break;
      }
      c.queued.clear();
    }
    dirty_.clear();
  }

  int listen_fd_;
  State& state_;
  BrokerOptions options_;
  int epoll_ = -1;
  int owner_fd_ = -1;
  pid_t asker_pid_ = 0;  // the spin's asker, watched through asker_fd_
  int asker_fd_ = -1;
  bool asker_gone_ = true;
  bool stop_ = false;
  bool fifo_ = true;  // at its SCHED_FIFO priority now (when it has one: State::rt_priority)
  bool up_[kMaxInterfaces] = {};
  bool known_[kMaxInterfaces] = {};
  std::vector<Connection> connections_;
  std::vector<int> dirty_;  // connections with frames queued this round
  std::uint64_t opened_ = 0;
  TxRecord batch_[64];
};

}  // namespace

void run_broker(int listen_fd, State& state, const BrokerOptions& options) {
  Broker broker(listen_fd, state, options);
  broker.note_interfaces();
  broker.run();
}

}  // namespace canhil::userbus
