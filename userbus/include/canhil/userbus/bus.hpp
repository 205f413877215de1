// canhil/userbus/bus.hpp — the user-space CAN bus from canhil's side: its
// folder, its broker (started, found, stopped), its interfaces (added, brought
// up or down, removed) and a listing of its sockets. `canhil bus` is built on
// it; the programs on the bus reach it through the preload, libcanhil-bus.so.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace canhil::wire {
struct FaultRule;
}

namespace canhil::userbus {

struct State;

/// A bus that cannot be set up or reached, with what to do.
class BusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where the bus lives: the folder ($CANHIL_BUS_DIR, else /tmp/canhil-bus-<uid>),
/// the broker's socket and the shared state file.
struct BusPaths {
  std::string folder;
  std::string socket;
  std::string state;
  static BusPaths current();
};

struct BrokerOptions {
  /// How long a receiver whose buffer and backlog are full may read nothing
  /// while it could before the broker drops frames for it (the kernel drops at once:
  /// 0). The wait follows the receiver: each read it makes renews the grace,
  /// and while one of its threads is runnable but not running (a busy
  /// machine) or in an uninterruptible wait (a write to a busy disk) it is
  /// held by the machine, not stuck, and the wait goes on. A
  /// receiver that let the wait pass has frames dropped at once, counted,
  /// until it reads again: a stuck receiver costs the bus one grace.
  std::uint32_t grace_us = 10000;
  /// How many frames wait in the broker for a receiver whose buffer is full
  /// while the bus goes on for everyone else (about 100 bytes each): a slow
  /// or briefly starved reader (a normal-priority `candump` or `canhil
  /// timing` beside a real-time run) loses nothing and slows nobody. Only a
  /// full backlog makes the broker wait for its receiver, with the grace
  /// and patience below.
  std::uint32_t backlog_frames = 4096;
  /// The longest the broker waits for one full receiver in all, however it
  /// reads or waits for a CPU: what a receiver that is always runnable but
  /// never reads (a busy loop holding a socket) can cost the bus, once.
  std::uint32_t patience_us = 250000;
  /// The broker's SCHED_FIFO priority (0: the normal scheduler): above the
  /// emulated nodes' (40, their masters 41), since every frame's delivery and
  /// receive stamp is the broker's. Where the system refuses it (no root or
  /// CAP_SYS_NICE) the broker runs on the normal scheduler and says so in
  /// State::rt_priority. With it, the broker locks its memory. While a
  /// lockstep run asks it to look for frames before it sleeps (State::spin),
  /// it runs on the normal scheduler, so that its looking gives way to
  /// every other process.
  int rt_priority = 45;
  /// A process the broker lives no longer than (0: until `stop`).
  pid_t owner = 0;
};

/// The bus's state file, mapped; unmapped when destroyed.
class MappedState {
 public:
  /// The state of the bus at `paths`, or nullptr when there is none.
  static std::unique_ptr<MappedState> open(const BusPaths& paths);
  ~MappedState();
  MappedState(const MappedState&) = delete;
  MappedState& operator=(const MappedState&) = delete;
  State& state() { return *state_; }

 private:
  explicit MappedState(State* s) : state_(s) {}
  State* state_;
};

/// While it lives, the broker of the bus at `paths` keeps looking for the
/// next frame for `us` microseconds after each before it sleeps, giving way
/// to any other runnable thread meanwhile (State::spin). In a lockstep
/// run the next frame comes tens of microseconds after the last, and where an
/// idle core halts (a virtual machine's: WSL2, Docker Desktop, most CI) waking
/// a sleeping broker on another core costs more than that, at every hop. The
/// broker stops looking when the holder's process ends, however it ends.
class BrokerSpin {
 public:
  /// Throws BusError when the bus has no state to map.
  BrokerSpin(const BusPaths& paths, std::uint32_t us);
  ~BrokerSpin();
  BrokerSpin(const BrokerSpin&) = delete;
  BrokerSpin& operator=(const BrokerSpin&) = delete;

 private:
  std::unique_ptr<MappedState> mapped_;
  std::uint64_t word_ = 0;
};

/// Whether a broker answers at the bus's socket.
bool broker_alive(const BusPaths& paths);

/// Starts a broker for the bus at `paths`, reclaiming the files of one that
/// died; the broker is a child of the calling process, in its own session.
/// Throws BusError when one already runs or the folder cannot be used.
pid_t start_broker(const BusPaths& paths, const BrokerOptions& options);

/// Creates the interfaces `names` (or brings them up when they exist).
/// Returns the names it created.
std::vector<std::string> add_interfaces(const BusPaths& paths, const std::vector<std::string>& names);

/// Brings interface `name` up or down, as `ip link set dev NAME up|down`.
void set_interface_up(const BusPaths& paths, const std::string& name, bool up);

/// start_broker() for a broker that outlives the caller (`canhil bus up`):
/// started from a process of its own whose standard streams are /dev/null, so
/// that it holds none of the caller's terminal or pipes. BusError as
/// start_broker's.
void start_broker_detached(const BusPaths& paths, const BrokerOptions& options);

/// Runs `command` (a program, found on the PATH, and its arguments) on the bus
/// at `paths`: the bus's preload first in its LD_PRELOAD, CANHIL_BUS_DIR set;
/// waits for it, SIGINT and SIGTERM ignored meanwhile (the command's are its
/// own). Returns its wait status (waitpid's). BusError when no preload is
/// found or no process can be started; a program that cannot be run ends
/// with status 127, saying why on stderr.
int run_on_bus(const BusPaths& paths, const std::vector<std::string>& command);

/// Removes the interfaces `names` (their bound sockets get ENODEV, as when a
/// kernel interface is deleted).
void remove_interfaces(const BusPaths& paths, const std::vector<std::string>& names);

/// Stops the broker (every socket on the bus is closed under its programs)
/// and removes the bus's files. Nothing when no broker runs.
void stop_broker(const BusPaths& paths);

/// One line per interface and per socket: name, index, state, counters; each
/// socket's process, binding, filters and counters.
std::string describe(const BusPaths& paths);

/// What the bus's interfaces have carried: per interface, frames sent on it
/// and copies dropped at a full receiver (drops are also each socket's, and
/// reach its program as SO_RXQ_OVFL).
struct InterfaceCounts {
  std::string name;
  std::uint64_t frames = 0;
  std::uint64_t dropped = 0;
};
std::vector<InterfaceCounts> interface_counts(const BusPaths& paths);

/// How often and how long the whole bus waited for a receiver whose
/// backlog was full (BrokerOptions::backlog_frames).
struct BusWaits {
  std::uint64_t count = 0;
  std::uint64_t total_us = 0;
  std::uint64_t longest_us = 0;
};
BusWaits broker_waits(const BusPaths& paths);

/// What `canhil bus exec` says at the end of its command: the frames its
/// receivers lost on interfaces `names` since `before` (each also counted on
/// its socket, SO_RXQ_OVFL) and, on a bus of its own (`own_bus`), the
/// broker's waits for full receivers. Empty when there is nothing to say.
std::string exec_report(const BusPaths& paths, const std::vector<std::string>& names,
                        const std::vector<InterfaceCounts>& before, bool own_bus);

/// How the bus's broker is scheduled: "SCHED_FIFO 45, memory locked", or
/// "normal scheduler" where the system refused a real-time priority.
std::string broker_scheduling(const BusPaths& paths);

/// A valid interface name (1 to 15 characters, no '/', ':' or white space), or
/// BusError naming what is wrong.
void check_interface_name(const std::string& name);

/// libcanhil-bus.so: $CANHIL_BUS_PRELOAD, else installed in the library
/// folder beside the running program's (../lib/...), else the build tree's.
/// BusError when none exists.
std::string find_preload();

/// For canhil's own programs, so that a user types nothing more than on a
/// kernel with vcan: when this process cannot open a CAN socket (the kernel
/// has no CAN), is not on the user-space bus already and a bus runs, it is
/// started again (execv of /proc/self/exe with `argv`) with the preload
/// (find_preload) in LD_PRELOAD, and says so on stderr. Returns when there is
/// nothing to do or no preload to start with (the kernel then answers); does
/// not return when it started itself again.
void join_bus_if_needed(char** argv);

// ---- Timed interfaces (docs/wire.md) --------------------------------------

/// An interface's wire, as `ip link set can0 type can bitrate ...` sets a
/// CAN device's: what is not given stays as it is.
struct LinkSettings {
  std::optional<std::uint32_t> bit_rate;       ///< bit/s; 0: instant delivery, no wire (a vcan)
  std::optional<std::uint32_t> data_bit_rate;  ///< CAN FD's data phase; 0: the bit rate
  std::optional<std::int32_t> restart_ms;      ///< after bus-off; 0: only on restart_link
  std::optional<std::uint32_t> tx_queue;       ///< a controller's transmit queue (txqueuelen), frames
};
/// BusError for a missing interface or a value out of range.
void set_link(const BusPaths& paths, const std::string& name, const LinkSettings& settings);
/// Settings as `ip link` words: "bitrate 500000 dbitrate 2000000 restart-ms
/// 100 txqueuelen 10", any of them; BusError naming a word it does not know
/// or a value that is not a whole number.
LinkSettings parse_link(const std::vector<std::string>& words);

/// Restarts the bus-off controllers on interface `name` (`ip link set can0
/// type can restart`); BusError when it has no wire or none is bus-off.
void restart_link(const BusPaths& paths, const std::string& name);

/// A wire fault on interface `name` (`canhil bus fault`): its times from
/// now, its controller a process's pid, which must have a controller there.
/// BusError otherwise.
void add_bus_fault(const BusPaths& paths, const std::string& name, const wire::FaultRule& rule);
/// Ends every wire fault on interface `name`.
void clear_bus_faults(const BusPaths& paths, const std::string& name);

/// A controller on a timed interface as the broker last said.
struct ControllerView {
  int pid = 0;
  int socket = -1;      ///< the socket whose own controller it is (canhil's emulated nodes), -1: the process's
  std::string program;  ///< /proc/PID/comm
  std::string interface;
  std::string state;  ///< "error-active", "error-warning", "error-passive", "bus-off"
  unsigned tec = 0;
  unsigned rec = 0;
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t errors = 0;
  std::uint64_t bus_offs = 0;
  std::uint64_t restarts = 0;
  std::uint64_t refused = 0;  ///< writes answered ENOBUFS
  unsigned queued = 0;
};
std::vector<ControllerView> controllers(const BusPaths& paths);

/// The process on interface `name` named `who` (its pid, or its program as
/// /proc/PID/comm says), or 0 when none has a controller there.
int controller_pid(const BusPaths& paths, const std::string& name, const std::string& who);

/// How late the bus delivers, as a receiver sees it: `frames` frames sent
/// `interval_us` apart on interface `name` by one process and read by
/// another (this one, at SCHED_FIFO 40 where it may), each read's time
/// against the frame's write (the whole hop) and against its receive stamp
/// (on a timed interface: the model's ideal end of frame).
struct DeliveryProbe {
  int received = 0;
  int out_of_order = 0;  ///< frames read before one stamped or written earlier
  bool fifo = false;     ///< the receiver ran at SCHED_FIFO
  double after_write_p50_us = 0;
  double after_write_p99_us = 0;
  double after_stamp_p50_us = 0;
  double after_stamp_p99_us = 0;
  std::int64_t last_written = 0;
};
/// How the probe's receiver waits for a frame. Asleep in a blocking read, it
/// is late by the bus's lateness and its own wake-up, which is the system's
/// (the same on a real adapter). Awake, it sleeps until the next frame could
/// be written and then polls without blocking: what it measures is the bus's
/// own lateness alone.
enum class ProbeReader : std::uint8_t { kAsleep, kAwake };
DeliveryProbe probe_delivery(const BusPaths& paths, const std::string& name, int frames, int interval_us,
                             ProbeReader reader = ProbeReader::kAsleep);
/// The machine's own wake-up, the reference for the bus's lateness: a
/// thread at the broker's SCHED_FIFO priority sleeping until an instant
/// every interval, how late it runs (what the broker's timer meets too).
struct WakeupProbe {
  bool fifo = false;
  int priority = 0;  ///< its SCHED_FIFO priority, when fifo
  double p50_us = 0;
  double p99_us = 0;
};
WakeupProbe probe_wakeup(int wakeups, int interval_us, int priority);

struct BusProbe {
  DeliveryProbe instant;      ///< an instant bus, the reader asleep
  DeliveryProbe timed;        ///< at the bit rate, the reader asleep
  DeliveryProbe timed_awake;  ///< at the bit rate, the reader awake
  WakeupProbe machine;        ///< the machine's own wake-up, in the same run
};
/// probe_delivery on a bus of its own (a fresh folder, vcan0), instant and
/// then at `bit_rate`, in the same run (`canhil bench --part wire`).
BusProbe probe_bus(int frames, int interval_us, std::uint32_t bit_rate);

/// Runs the broker's loop in this process until it is stopped or its owner
/// ends (what start_broker's child runs). listen_fd: the bound listening socket.
void run_broker(int listen_fd, State& state, const BrokerOptions& options);

}  // namespace canhil::userbus
