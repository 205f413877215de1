// The broker: one process per bus that routes every frame a socket sends to
// every socket whose binding and filters want it, with the kernel's CAN_RAW
// rules (net/can/af_can.c's filter lists, net/can/raw.c's loopback, own
// messages and joined filters). One thread, one epoll; each socket a
// SOCK_SEQPACKET connection. A timed interface's frames go through its wire
// model first (broker_wire.hpp), and reach their sockets at their end of
// frame, from a timer.
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
#include <deque>
#include <vector>

#include "broker_connection.hpp"
#include "broker_filters.hpp"
#include "broker_system.hpp"
#include "broker_wire.hpp"
#include "canhil/base/preload.hpp"
#include "canhil/base/process.hpp"
#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {
namespace {

std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

// Past the time shim (a broker started under it must not read a clock that stands still).
std::int64_t monotonic_ns() { return ::canhil::preload::real_monotonic_ns(); }

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
    if (timer_.fd() >= 0) watch(timer_.fd());
    wire_.sync(monotonic_ns());
  }

  ~Broker() {
    for (Connection& c : connections_) {
      if (c.fd >= 0) close(c.fd);
    }
    if (owner_fd_ >= 0) close(owner_fd_);
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
      int n = spin_.look(epoll_, events, 64);
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
        } else if (fd == timer_.fd()) {
          timer_.fired(wire_.next_due());
          advance_wire();
        } else {
          serve(fd, events[i].events);
        }
      }
    }
  }

 private:
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
    if (c.backlogged) {
      --backlogged_;  // what it had not read is nobody's now
      close_round_if_delivered();
    }
    epoll_ctl(epoll_, EPOLL_CTL_DEL, c.fd, nullptr);
    close(c.fd);
    const int slot = c.slot;
    const ControllerKey key = slot >= 0 ? key_of(c) : ControllerKey{};
    c = Connection{};
    if (slot >= 0) {
      state_.sockets[slot].in_use.store(0, std::memory_order_release);
      // Its controllers leave the timed buses: its own, or its process's with its last socket.
      const bool more = std::any_of(connections_.begin(), connections_.end(),
                                    [&](Connection& o) { return o.fd >= 0 && o.slot >= 0 && key_of(o) == key; });
      if (!more) wire_.leave(key);
    }
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
    if ((events & EPOLLOUT) != 0 && c.backlogged) {  // its reader made room
      send_backlog(c);
      close_round_if_delivered();
      if ((events & (EPOLLIN | EPOLLHUP | EPOLLERR)) == 0) return;
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
    // A hang-up is read as the end of the connection, once its frames are routed.
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
    Welcome w{claim_socket(state_, h.pid, c.fd)};
    c.slot = w.slot >= 0 ? w.slot : -1;
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
      } else {
        wire_done_.clear();  // a lockstep instant's deliveries are in the sockets before the answer
        answer = wire_.control(r, monotonic_ns(), wire_done_);
        hand_wire(false);
      }
      arm_timer();
    }
    if (n > 0) send(c.fd, &answer, sizeof answer, MSG_NOSIGNAL | MSG_DONTWAIT);
    drop(c);
  }

  /// An interface went down or away: every socket bound to it is told, as
  /// raw.c's notifier tells it (ENETDOWN; ENODEV and unbound when removed).
  void interfaces_changed() {
    advance_wire();
    wire_.sync(monotonic_ns());
    arm_timer();
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
    c.options = read_options(s);
    if (c.options.rcvbuf != c.applied_rcvbuf && c.options.rcvbuf > 0) {
      // What the program asked of its receive buffer is the broker's send buffer towards it.
      const int size = c.options.rcvbuf / 2;
      setsockopt(c.fd, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
      c.applied_rcvbuf = c.options.rcvbuf;
    }
    return c.options;
  }

  void route(Connection& sender, const TxRecord& record) {
    Interface* iface = find_interface(state_, record.ifindex);
    if (iface == nullptr || iface->up.load(std::memory_order_relaxed) == 0) {
      return wire_.refund(key_of(sender), record.ifindex);  // the preload counted it into a timed queue
    }
    state_.sockets[sender.slot].sent.fetch_add(1, std::memory_order_relaxed);
    if (!wire_.timed(record.ifindex)) iface->frames.fetch_add(1, std::memory_order_relaxed);
    if (wire_.timed(record.ifindex)) {
      const std::int64_t now = monotonic_ns();
      for (Connection& c : connections_) {  // every process on the interface is a controller there
        if (c.fd < 0 || c.slot < 0) continue;
        const Options& o = options(c);
        if (o.bound && (o.ifindex == 0 || o.ifindex == record.ifindex)) wire_.join(key_of(c), record.ifindex);
      }
      wire_done_.clear();
      wire_.submit(key_of(sender), sender.opened, record, now, wire_done_);
      if (!wire_done_.empty()) hand_wire(false);
      iface->frames.fetch_add(1, std::memory_order_release);  // after its next event is published
      arm_timer();
      return;
    }
    // A virtual interface has no wire: with loopback off nobody hears the frame.
    if ((options(sender).flags & kLoopback) == 0) return;
    instant_.ifindex = record.ifindex;
    instant_.size = record.size;
    std::memcpy(instant_.frame, record.frame, record.size);
    to_sockets(instant_, &sender, now_ns(), true);
  }

  /// What the timed wires have done by now, handed to the sockets.
  void advance_wire() {
    wire_done_.clear();
    wire_.advance(monotonic_ns(), wire_done_);
    hand_wire(true);
    arm_timer();
  }

  /// wire_done_ to the sockets, stamped at its time (`at_their_time`: a real
  /// wire's end of frame) or now (a driven wire's, in a lockstep run's time).
  void hand_wire(bool at_their_time) {
    const std::int64_t to_realtime = at_their_time ? realtime_offset() : 0;
    for (const WireDelivery& d : wire_done_) deliver_wire(d, at_their_time ? d.at_ns + to_realtime : now_ns());
    flush();
  }

  /// CLOCK_REALTIME less the monotonic clock, read between two monotonic
  /// readings close together (a preemption between the reads would move
  /// every stamp), once a second: a stamp is the frame's end on both clocks.
  std::int64_t realtime_offset() {
    const std::int64_t now = monotonic_ns();
    if (now - offset_read_at_ < 1'000'000'000 && offset_read_at_ != 0) return to_realtime_;
    std::int64_t best = INT64_MAX;
    for (int k = 0; k < 8; ++k) {
      const std::int64_t before = monotonic_ns();
      const std::int64_t real = now_ns();
      const std::int64_t after = monotonic_ns();
      if (after - before < best) {
        best = after - before;
        to_realtime_ = real - before / 2 - after / 2;
      }
      if (best < 2000) break;
    }
    offset_read_at_ = now;
    return to_realtime_;
  }

  /// A wire's frame (at its end of frame) or error frame to every socket that
  /// takes it: on the sender's controller its local echo (loopback, own
  /// messages, MSG_CONFIRM); on the others the frame as received from a wire,
  /// unless that controller missed it (bus-off, cut off). An error frame goes
  /// to the reporting controller's sockets whose CAN_RAW_ERR_FILTER asks.
  void deliver_wire(const WireDelivery& d, std::int64_t stamp) {
    const Connection* sender = nullptr;
    for (const Connection& c : connections_) {
      if (d.tag != 0 && c.fd >= 0 && c.opened == d.tag) sender = &c;
    }
    to_sockets(d, sender, stamp, false);
  }

  /// `d` to every socket that takes it, stamped `stamp`; `instant`: a
  /// virtual interface's frame, which every socket gets as a local echo.
  void to_sockets(const WireDelivery& d, const Connection* sender, std::int64_t stamp, bool instant) {
    canid_t can_id = 0;
    std::memcpy(&can_id, d.frame, sizeof can_id);
    const bool echo = sender != nullptr && (sender->options.flags & kLoopback) != 0;
    RxRecord out{};
    out.stamp_ns = stamp;
    out.ifindex = d.ifindex;
    out.size = d.size;
    std::memcpy(out.frame, d.frame, d.size);
    for (Connection& c : connections_) {
      if (c.fd < 0 || c.slot < 0) continue;
      const Options& o = options(c);
      if (!o.bound || (o.ifindex != 0 && o.ifindex != d.ifindex)) continue;
      bool local = true;
      if (!instant) {
        const ControllerKey key = key_of(c);
        local = key == d.from;
        if (d.error ? !local : (local ? !echo : std::count(d.missed.begin(), d.missed.end(), key) > 0)) continue;
      }
      const bool own = &c == sender;
      if (own && (o.flags & kRecvOwn) == 0) continue;
      if (d.size != CAN_MTU && (o.flags & kFdFrames) == 0) continue;
      if (!wants(o, can_id)) continue;
      out.msg_flags = 0;
      if (!d.error && local) out.msg_flags = MSG_DONTROUTE | (own ? static_cast<std::uint32_t>(MSG_CONFIRM) : 0U);
      deliver(c, out);
    }
  }

  /// The timer set for the wires' next event (none when they have none).
  void arm_timer() { timer_.arm(wire_.next_due()); }

  /// The controller c's frames go through on a timed interface: its own, or its process's.
  ControllerKey key_of(Connection& c) {
    const bool own = (options(c).flags & kOwnController) != 0;
    return ControllerKey{state_.sockets[c.slot].pid, own ? c.slot : -1};
  }

  /// Queues `r` for `c`, with the count of c's drops so far (SO_RXQ_OVFL).
  void deliver(Connection& c, RxRecord& r) {
    r.drops = state_.sockets[c.slot].drops.load(std::memory_order_relaxed);
    if (c.queued.empty()) dirty_.push_back(c.fd);
    c.queued.push_back(r);
  }

  /// One round: what route() queued handed to its sockets, State::rounds odd
  /// meanwhile and for as long as a receiver's backlog holds frames (a frame
  /// is in every socket that takes it only once no backlog holds one).
  void flush() {
    if (dirty_.empty()) return;
    if (!round_open_) {
      state_.rounds.fetch_add(1, std::memory_order_acq_rel);
      round_open_ = true;
    }
    hand_over();
    close_round_if_delivered();
  }

  void close_round_if_delivered() {
    if (!round_open_ || backlogged_ > 0) return;
    state_.rounds.fetch_add(1, std::memory_order_release);
    round_open_ = false;
  }

  /// Sends every connection what this round routed to it, in one call each;
  /// what does not fit in a receiver's buffer waits in its backlog (keep).
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
      // Behind a backlog, new frames wait their turn.
      const std::size_t done =
          c.backlog.empty() ? send_records(c, c.queued.size(), [&c](std::size_t k) -> RxRecord& { return c.queued[k]; })
                            : 0;
      if (done < c.queued.size()) keep(c, done);
      c.queued.clear();
    }
    dirty_.clear();
  }

  /// Sends up to `count` records, `at(0)` first, to c's socket without
  /// waiting: how many went (all when the program is going: its end is read
  /// next, and what it did not take is nobody's).
  template <typename At>
  std::size_t send_records(Connection& c, std::size_t count, At at) {
    Socket& s = state_.sockets[c.slot];
    std::size_t done = 0;
    while (done < count) {
      const std::size_t n = std::min<std::size_t>(count - done, 64);
      mmsghdr out[64] = {};
      iovec parts[64];
      for (std::size_t k = 0; k < n; ++k) {
        RxRecord& r = at(done + k);
        parts[k] = {&r, kRxHeader + r.size};
        out[k].msg_hdr.msg_iov = &parts[k];
        out[k].msg_hdr.msg_iovlen = 1;
      }
      const int sent = sendmmsg(c.fd, out, static_cast<unsigned>(n), MSG_DONTWAIT | MSG_NOSIGNAL);
      if (sent > 0) {
        done += static_cast<std::size_t>(sent);
        c.overrun = false;
        s.received.fetch_add(static_cast<std::uint64_t>(sent), std::memory_order_release);
        continue;
      }
      if (sent < 0 && errno != EAGAIN) return count;
      break;
    }
    return done;
  }

  /// What did not fit in c's buffer, c.queued from `from` on, waits in its
  /// backlog, sent as the receiver reads (EPOLLOUT), while the bus goes on
  /// for everyone else. Only a full backlog makes the broker wait for a
  /// receiver (room_came: while it reads or waits for a CPU, up to the
  /// patience): the one way a flood is slowed to its slowest reader. A
  /// receiver that lets the grace pass while it could read is stuck: its
  /// backlog and these frames are dropped, counted, and so is what comes for
  /// it until it reads again.
  void keep(Connection& c, std::size_t from) {
    Socket& s = state_.sockets[c.slot];
    // A program that sized its buffer (SO_RCVBUF) has what it asked for, as
    // on the kernel: a backlog of one frame, no more.
    const std::size_t cap = c.options.rcvbuf > 0 ? 1 : std::max<std::size_t>(options_.backlog_frames, 1);
    for (std::size_t k = from; k < c.queued.size(); ++k) {
      if (!c.overrun && c.backlog.size() >= cap) {
        // A socket that has never read a frame (one a program only sends on)
        // is no reader to wait for: the kernel's treatment, dropped when full.
        if (s.taken.load(std::memory_order_acquire) != 0) {
          const std::int64_t waited_from = monotonic_ns();
          while (c.backlog.size() >= cap && room_came(c.fd, s.pid, s.taken, options_.grace_us, options_.patience_us))
            send_backlog(c);
          count_wait(monotonic_ns() - waited_from);
        }
        if (c.backlog.size() >= cap) {
          c.overrun = true;
          for (const RxRecord& r : c.backlog) lose(s, r);
          c.backlog.clear();
        }
      }
      if (c.overrun) {
        lose(s, c.queued[k]);
        continue;
      }
      c.backlog.push_back(c.queued[k]);
    }
    set_backlogged(c, !c.backlog.empty());
  }

  void count_wait(std::int64_t ns) {
    const auto us = static_cast<std::uint64_t>(ns / 1000);
    state_.waits.fetch_add(1, std::memory_order_relaxed);
    state_.waited_us.fetch_add(us, std::memory_order_relaxed);
    if (us > state_.longest_wait_us.load(std::memory_order_relaxed))
      state_.longest_wait_us.store(us, std::memory_order_relaxed);
  }

  void send_backlog(Connection& c) {
    const std::size_t sent =
        send_records(c, c.backlog.size(), [&c](std::size_t k) -> RxRecord& { return c.backlog[k]; });
    c.backlog.erase(c.backlog.begin(), c.backlog.begin() + static_cast<std::ptrdiff_t>(sent));
    set_backlogged(c, !c.backlog.empty());
  }

  /// Whether c waits for room (EPOLLOUT watched) with frames in its backlog.
  void set_backlogged(Connection& c, bool backlogged) {
    if (c.backlogged == backlogged) return;
    c.backlogged = backlogged;
    backlogged_ += backlogged ? 1 : -1;
    epoll_event e{};
    e.events = EPOLLIN | (backlogged ? EPOLLOUT : 0U);
    e.data.fd = c.fd;
    epoll_ctl(epoll_, EPOLL_CTL_MOD, c.fd, &e);
  }

  /// A frame `r` lost for socket `s`: counted on the socket (SO_RXQ_OVFL) and its interface.
  void lose(Socket& s, const RxRecord& r) {
    s.drops.fetch_add(1, std::memory_order_relaxed);
    if (Interface* i = find_interface(state_, r.ifindex)) i->dropped.fetch_add(1, std::memory_order_relaxed);
  }

  int listen_fd_;
  State& state_;
  BrokerOptions options_;
  int epoll_ = -1;
  int owner_fd_ = -1;
  Spin spin_{state_};
  bool stop_ = false;
  bool round_open_ = false;  // State::rounds is odd: a round under way, or a backlog not yet delivered
  int backlogged_ = 0;       // connections with frames in their backlog
  bool up_[kMaxInterfaces] = {};
  bool known_[kMaxInterfaces] = {};
  std::vector<Connection> connections_;
  std::vector<int> dirty_;  // connections with frames queued this round
  std::uint64_t opened_ = 0;
  TxRecord batch_[64];
  BrokerWire wire_{state_};
  WireTimer timer_;
  WireDelivery instant_;             // a virtual interface's frame, routed at once (reused)
  std::int64_t to_realtime_ = 0;     // realtime_offset()'s last reading,
  std::int64_t offset_read_at_ = 0;  // taken then (monotonic)
  std::vector<WireDelivery> wire_done_;
};

}  // namespace

void run_broker(int listen_fd, State& state, const BrokerOptions& options) {
  Broker broker(listen_fd, state, options);
  broker.note_interfaces();
  broker.run();
}

}  // namespace canhil::userbus
