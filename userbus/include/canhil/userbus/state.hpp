// canhil/userbus/state.hpp — what the user-space CAN bus's processes share: the
// bus folder, the state file every process maps (the interfaces and every
// socket's options, so a process that reads or writes a socket needs no round
// trip to the broker), and the records on a socket's connection to the broker.
//
// Header-only and libc only (the preload, libcanhil-bus.so, uses it inside
// programs canhil did not build: no exceptions, no heap). docs/vcan.md says
// how the parts fit.
//
//   <bus folder>/bus.sock   the broker's listening socket (SOCK_SEQPACKET)
//   <bus folder>/state      the shared state below (0600, the folder 0700)
//
// One CAN_RAW socket of a program is one connection to the broker: the
// program's descriptor is the connection's own end, a real socket, so read,
// poll, select, epoll, O_NONBLOCK, dup, fork and exec work on it as on the
// kernel's. The broker routes each frame a connection sends to every other
// connection whose options (in the state file) want it.
#pragma once

#include <linux/can.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace canhil::userbus {

inline constexpr std::uint32_t kMagic = 0x43414e42;  // "CANB"
inline constexpr std::uint32_t kVersion = 6;
inline constexpr int kMaxInterfaces = 32;
inline constexpr int kMaxSockets = 1024;
inline constexpr int kMaxFilters = 512;  // CAN_RAW_FILTER_MAX, as the kernel
/// Controllers on timed interfaces: one per process and interface (docs/wire.md).
inline constexpr int kMaxControllers = 256;
/// A new interface's restart delay after bus-off (ms) and transmit queue
/// (frames: a CAN device's txqueuelen, as can-dev sets it).
inline constexpr std::int32_t kDefaultRestartMs = 100;
inline constexpr std::uint32_t kDefaultTxQueue = 10;
/// The bus's interface indices start here, far above what a machine's kernel
/// numbers its own interfaces, so that one never stands for the other.
inline constexpr int kFirstIndex = 1 << 20;
/// An interface's MTU when created: a vcan's default (CAN FD frames pass;
/// SIOCSIFMTU sets CAN_MTU, classic frames only, as `ip link set mtu 16`).
inline constexpr std::uint32_t kInterfaceMtu = CANFD_MTU;

/// The bus's folder: $CANHIL_BUS_DIR, else /tmp/canhil-bus-<uid>. Written to
/// `out` (of `size` bytes); false when it does not fit.
inline bool bus_folder(char* out, std::size_t size) noexcept {
  const char* given = std::getenv("CANHIL_BUS_DIR");
  const int n = (given != nullptr && *given != '\0') ? std::snprintf(out, size, "%s", given)
                                                     : std::snprintf(out, size, "/tmp/canhil-bus-%u", getuid());
  return n > 0 && static_cast<std::size_t>(n) < size;
}

/// `folder`/`name` into `out`; false when it does not fit (a socket's path
/// has at most 107 characters).
inline bool bus_path(char* out, std::size_t size, const char* folder, const char* name) noexcept {
  const int n = std::snprintf(out, size, "%s/%s", folder, name);
  return n > 0 && static_cast<std::size_t>(n) < size;
}

/// A small lock of the state file, shared between processes (a spin lock: it
/// is held for a few stores, never across a call).
struct SharedLock {
  std::atomic<std::uint32_t> word{0};
  void lock() noexcept {
    std::uint32_t expected = 0;
    while (!word.compare_exchange_weak(expected, 1, std::memory_order_acquire)) {
      expected = 0;
    }
  }
  void unlock() noexcept { word.store(0, std::memory_order_release); }
};

struct Interface {
  std::atomic<std::uint32_t> in_use;
  std::atomic<std::uint32_t> up;  ///< IFF_UP
  std::int32_t index;
  std::atomic<std::uint32_t> mtu;
  char name[16];                       // IFNAMSIZ, NUL-terminated
  std::atomic<std::uint64_t> frames;   ///< frames sent on it
  std::atomic<std::uint64_t> dropped;  ///< copies dropped at a full receiver
  // Its wire (docs/wire.md), set by `canhil bus link NAME bitrate ...` and
  // read by the broker (told through kControlInterfacesChanged) and by the
  // preload (the transmit queue's length).
  std::atomic<std::uint32_t> bit_rate;       ///< bit/s; 0: instant delivery, no wire
  std::atomic<std::uint32_t> data_bit_rate;  ///< CAN FD's data phase; 0: the bit rate
  std::atomic<std::int32_t> restart_ms;      ///< after bus-off: 0 only on `restart`, else this many ms
  std::atomic<std::uint32_t> tx_queue;       ///< frames a controller's queue holds (txqueuelen); one more: ENOBUFS
  /// The wire's figures, written by the broker: time it carried bits and
  /// time since its wire began (the load is their ratio), errors on it.
  std::atomic<std::uint64_t> busy_ns;
  std::atomic<std::uint64_t> wire_ns;
  std::atomic<std::uint64_t> error_frames;
  /// The wire's clock is a lockstep run's (kControlWireTime), not the broker's own.
  std::atomic<std::uint32_t> driven;
  std::atomic<std::uint64_t> delivered;  ///< frames its wire has delivered whole (at their end of frame)
  /// A driven wire's next event in its own time (ns), written by the broker
  /// before it counts the frame that moved it in `frames`; INT64_MAX: none.
  std::atomic<std::int64_t> next_due_ns;
};

/// One CAN controller on a timed interface: a process's adapter (every socket
/// it holds on that interface shares it), or one socket's own (kOwnController:
/// each of canhil's emulated nodes, as each is a board of its own). Claimed
/// by the first of the preload (a frame sent) and the broker (a socket bound
/// there) under State::lock; freed by the broker once its process holds no
/// socket there and its queue is empty.
struct Controller {
  std::atomic<std::uint32_t> in_use;
  std::int32_t pid;
  std::int32_t ifindex;
  std::int32_t slot;  ///< the socket whose own controller it is, -1: the process's
  /// Frames given and not yet sent or dropped: the preload counts one up
  /// before it hands a frame to the broker (ENOBUFS at the interface's
  /// tx_queue), the broker one down at its end of frame.
  std::atomic<std::uint32_t> queued;
  std::atomic<std::uint64_t> refused;  ///< writes answered ENOBUFS (the preload counts)
  // As the broker's wire model last said (ControllerStatus).
  std::atomic<std::uint32_t> state;  ///< ControllerState: 0 active, 1 warning, 2 passive, 3 bus-off
  std::atomic<std::uint32_t> tec;
  std::atomic<std::uint32_t> rec;
  std::atomic<std::uint64_t> sent;
  std::atomic<std::uint64_t> received;
  std::atomic<std::uint64_t> errors;
  std::atomic<std::uint64_t> bus_offs;
  std::atomic<std::uint64_t> restarts;
};

/// Option flags of a socket (Socket::flags).
enum SocketFlag : std::uint32_t {
  kLoopback = 1U << 0,       ///< CAN_RAW_LOOPBACK (default on)
  kRecvOwn = 1U << 1,        ///< CAN_RAW_RECV_OWN_MSGS
  kFdFrames = 1U << 2,       ///< CAN_RAW_FD_FRAMES
  kJoinFilters = 1U << 3,    ///< CAN_RAW_JOIN_FILTERS
  kTimestamp = 1U << 4,      ///< SO_TIMESTAMP or SO_TIMESTAMPNS
  kTimestampNs = 1U << 5,    ///< SO_TIMESTAMPNS (nanoseconds win, as in the kernel)
  kRxqOverflow = 1U << 6,    ///< SO_RXQ_OVFL
  kTimestampNew = 1U << 7,   ///< set with SO_TIMESTAMP(NS)_NEW: 64-bit time in the control message's type
  kStampKept = 1U << 8,      ///< SOCK_TIMESTAMP: a read keeps its frame's time for SIOCGSTAMP
  kOwnController = 1U << 9,  ///< a controller of its own on a timed interface (canhil_userbus_own_controller)
};

/// One CAN_RAW socket's options, written by the processes that hold it (under
/// `lock`, `seq` bumped so the broker sees a change) and read by the broker
/// when it routes a frame.
struct Socket {
  std::atomic<std::uint32_t> in_use;
  std::atomic<std::uint32_t> seq;  ///< bumped by every change of the options below
  SharedLock lock;
  std::int32_t pid;      ///< the process that opened it
  std::int32_t ifindex;  ///< bound interface, 0 for all
  std::uint32_t bound;
  std::uint32_t flags;     ///< SocketFlag
  std::uint32_t err_mask;  ///< CAN_RAW_ERR_FILTER
  std::int32_t rcvbuf;     ///< SO_RCVBUF as getsockopt answers (the kernel's doubled value)
  std::int32_t sndbuf;     ///< SO_SNDBUF likewise
  std::uint32_t filter_count;
  can_filter filters[kMaxFilters];
  char peer[16];                            ///< the connection's autobound name ("\0" and five hex digits)
  std::atomic<std::int32_t> pending_error;  ///< an errno a read or write reports once (SO_ERROR)
  std::atomic<std::int64_t> last_stamp_ns;  ///< the last frame read's time (SIOCGSTAMP), -1 before any
  std::atomic<std::uint32_t> drops;         ///< copies dropped at this socket (SO_RXQ_OVFL)
  /// Records (frames and errors) the broker has given the socket, counted
  /// once they are in it: `received - taken` is what waits there, a record
  /// being handed over at that moment aside.
  std::atomic<std::uint64_t> received;
  std::atomic<std::uint64_t> sent;
  /// Records the processes holding the socket have read from it (the
  /// preload counts each one).
  std::atomic<std::uint64_t> taken;
};

struct State {
  std::uint32_t magic;
  std::uint32_t version;
  std::int32_t broker_pid;
  std::uint32_t grace_us;        ///< how long a full receiver may read nothing while it could before frames drop for it
  std::uint32_t patience_us;     ///< the longest the broker waits for one full receiver in all
  std::uint32_t backlog_frames;  ///< frames that wait in the broker for a full receiver
  /// The times the broker waited for a receiver whose backlog was full (the
  /// whole bus waits meanwhile), the time it waited in all and the longest
  /// wait, counted by the broker: `canhil bus list` and `bus exec` show them.
  std::atomic<std::uint64_t> waits;
  std::atomic<std::uint64_t> waited_us;
  std::atomic<std::uint64_t> longest_wait_us;
  /// The broker's scheduling as it got it: SCHED_FIFO priority (0: the
  /// normal scheduler) and whether its memory is locked (BrokerOptions).
  std::int32_t rt_priority;
  std::uint32_t memory_locked;
  SharedLock lock;  ///< held to add or remove an interface
  std::atomic<std::uint32_t> interfaces_seq;
  /// How long the broker keeps looking for the next frame after each batch
  /// before it sleeps, giving way to any other runnable thread meanwhile,
  /// while the process that asked lives (a lockstep run: BrokerSpin): one
  /// word, spin_word(pid, microseconds), so that it is set and given back
  /// whole; 0: the broker sleeps at once.
  std::atomic<std::uint64_t> spin;
  std::atomic<std::uint64_t> spins;  ///< how many times the broker looked on so, counted by it
  /// The broker's rounds of handing frames to their sockets: odd while one
  /// is under way, or while a receiver's backlog still holds frames (its
  /// buffer was full), even between them. A program that has read a frame on one
  /// socket and then finds this even, or past the odd value it saw after
  /// that read, knows the frame is in every socket that takes it (canhil's
  /// lockstep: can_nodes::DeliveryFence, through canhil_userbus_rounds).
  std::atomic<std::uint64_t> rounds;
  Interface interfaces[kMaxInterfaces];
  Socket sockets[kMaxSockets];
  Controller controllers[kMaxControllers];
};

/// State::spin's word: who asked (a pid) and for how long (microseconds).
inline constexpr std::uint64_t spin_word(pid_t pid, std::uint32_t us) noexcept {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(pid)) << 32) | us;
}
inline constexpr pid_t spin_pid(std::uint64_t word) noexcept { return static_cast<pid_t>(word >> 32); }
inline constexpr std::uint32_t spin_us(std::uint64_t word) noexcept { return static_cast<std::uint32_t>(word); }

/// The interface called `name`, or nullptr.
inline Interface* find_interface(State& s, const char* name) noexcept {
  for (Interface& i : s.interfaces) {
    if (i.in_use.load(std::memory_order_acquire) != 0 && std::strncmp(i.name, name, sizeof i.name) == 0) return &i;
  }
  return nullptr;
}

/// The interface of index `index`, or nullptr.
inline Interface* find_interface(State& s, int index) noexcept {
  const int k = index - kFirstIndex;
  if (k < 0 || k >= kMaxInterfaces) return nullptr;
  Interface& i = s.interfaces[k];
  return i.in_use.load(std::memory_order_acquire) != 0 ? &i : nullptr;
}

/// The controller of process `pid` (socket `slot`'s own, -1: the process's) on interface `ifindex`, claimed when
/// `claim` and there is none yet (under State::lock); nullptr when there is
/// none (or no free row).
inline Controller* find_controller(State& s, std::int32_t pid, std::int32_t ifindex, std::int32_t slot,
                                   bool claim) noexcept {
  const auto is = [&](const Controller& c) { return c.pid == pid && c.ifindex == ifindex && c.slot == slot; };
  for (Controller& c : s.controllers) {
    if (c.in_use.load(std::memory_order_acquire) != 0 && is(c)) return &c;
  }
  if (!claim) return nullptr;
  s.lock.lock();
  Controller* found = nullptr;
  for (Controller& c : s.controllers) {
    const bool used = c.in_use.load(std::memory_order_acquire) != 0;
    if (used && is(c)) {
      found = &c;
      break;
    }
    if (!used && found == nullptr) found = &c;
  }
  if (found != nullptr && found->in_use.load(std::memory_order_relaxed) == 0) {
    found->pid = pid;
    found->ifindex = ifindex;
    found->slot = slot;
    found->queued.store(0);
    found->refused.store(0);
    found->state.store(0);
    found->tec.store(0);
    found->rec.store(0);
    found->sent.store(0);
    found->received.store(0);
    found->errors.store(0);
    found->bus_offs.store(0);
    found->restarts.store(0);
    found->in_use.store(1, std::memory_order_release);
  }
  s.lock.unlock();
  return found;
}

// ---- Records on a socket's connection ----------------------------------

/// The first record a process sends on a new connection.
struct Hello {
  std::uint32_t kind;  ///< kHelloSocket or kHelloControl
  std::int32_t pid;
};
inline constexpr std::uint32_t kHelloSocket = 1;
inline constexpr std::uint32_t kHelloControl = 2;

/// The broker's answer to a socket's hello: its slot in State::sockets, or
/// -errno when it has none left.
struct Welcome {
  std::int32_t slot;
};

/// A frame a process sends: the interface (the socket's bound one, or the
/// one sendto named) and the frame as the program wrote it.
struct TxRecord {
  /// The writer's lockstep time (canhil_shim_board_now), -1 outside a
  /// lockstep run: a driven wire takes the frame then.
  std::int64_t at_ns;
  std::int32_t ifindex;
  std::uint32_t size;  ///< CAN_MTU or CANFD_MTU
  unsigned char frame[CANFD_MTU];
};
inline constexpr std::size_t kTxHeader = offsetof(TxRecord, frame);

/// A frame (or an error) the broker delivers to a socket.
struct RxRecord {
  std::int64_t stamp_ns;    ///< CLOCK_REALTIME when the bus delivered it
  std::int32_t ifindex;     ///< the interface it arrived on
  std::uint32_t msg_flags;  ///< MSG_DONTROUTE, MSG_CONFIRM
  std::uint32_t drops;      ///< the socket's drops so far (SO_RXQ_OVFL)
  std::int32_t error;       ///< an errno to report instead of a frame (ENETDOWN, ENODEV), else 0
  std::uint32_t size;
  std::uint32_t pad;
  unsigned char frame[CANFD_MTU];
};
inline constexpr std::size_t kRxHeader = offsetof(RxRecord, frame);

inline constexpr std::uint32_t kControlInterfacesChanged = 1;  ///< also: an interface's wire settings changed
inline constexpr std::uint32_t kControlStop = 2;
inline constexpr std::uint32_t kControlRestart = 3;  ///< restart `ifindex`'s bus-off controllers (`pid`: one, 0: all)
inline constexpr std::uint32_t kControlFault = 4;    ///< add `fault` on `ifindex`
inline constexpr std::uint32_t kControlClearFaults = 5;  ///< end every fault on `ifindex`
inline constexpr std::uint32_t kControlWireTime = 6;     ///< run `ifindex`'s driven wire to `time_ns`, delivering

/// A wire fault for a running bus (`canhil bus fault`): wire::FaultRule's
/// fields, its times from when the broker takes it, its node a process.
struct FaultRequest {
  std::uint32_t kind;  ///< wire::FaultRule::Kind
  std::int64_t from_ns;
  std::int64_t until_ns;  ///< -1: for ever
  double rate;
  std::int32_t has_id;
  std::uint32_t id;
  std::int32_t pid;         ///< the process whose controller it names, 0: none
  std::int32_t slot;        ///< that process's socket whose own controller it is, -1: the process's
  std::uint32_t babble_id;  ///< kBabbling: the 11-bit id of its frames
};

/// What a control connection asks (one request, one answer: an int, 0 or -errno).
struct ControlRequest {
  std::uint32_t op;          ///< kControl*
  std::int32_t ifindex = 0;  ///< restart, fault, clear: the interface
  std::int32_t pid = 0;      ///< restart: the process whose controller, 0: every bus-off one
  FaultRequest fault{};      ///< fault: the rule
  std::int64_t time_ns = 0;  ///< wire time: the driven wire's time to run to
};

}  // namespace canhil::userbus
