// canhil/emulator/external_driver.hpp — a session in virtual time with the
// team's own processes (docs/lockstep.md): every robot's emulated nodes on
// its SocketCAN interface (one socket per node, as in real time), advanced on
// a simulated clock together with the physics, while the team's handler and
// agent run as separate processes under the time shim. At each instant where
// canhil sent frames, moved a process's wake-up or woke an agent through PMan,
// the driver waits (lockstep::Conductor::wait_quiet) until every process is
// done with that instant: blocked again, its frames seen on the bus, its
// PMan epilogue written. Frames the processes sent are handled in the same
// instant. Deterministic: the trace carries virtual times, in a fixed order.
//
// Not thread-safe: one thread drives it.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "canhil/can_nodes/delivery_fence.hpp"
#include "canhil/can_nodes/medium.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/emulator/bus_watch.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::emulator {

struct ExternalOptions {
  int receive_buffer_bytes = 1 << 20;  ///< per socket (SO_RCVBUFFORCE as root)
  bool record_trace = true;            ///< keep every bus's frames for trace()
  /// Check every bus against `canhil timing`'s rules as frames are seen, in
  /// constant memory: ftt_violations().
  bool check_timing = false;
  /// Wall time the processes may take from their start until they first all
  /// wait (loading configuration, building tables), and an agent for its first
  /// activation (its first cycle, where a team's agent builds its maps); then
  /// each instant has the conductor's answer limit (and, while the processes
  /// compute, its busy limit).
  Nanos start_limit = std::chrono::seconds(60);
};

/// A process did not become quiet within the conductor's answer limit: what()
/// names it and what canhil waited for. The run stops; its trace is kept.
class ProcessStuck : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ExternalDriver {
 public:
  /// Opens one socket per node and one observer socket per robot's interface.
  /// SetupError: no such interface, an interface down. `session` and
  /// `conductor` must outlive the driver.
  ExternalDriver(Session& session, lockstep::Conductor& conductor, ExternalOptions options = {});
  ~ExternalDriver();
  ExternalDriver(const ExternalDriver&) = delete;
  ExternalDriver& operator=(const ExternalDriver&) = delete;

  /// Runs until the virtual clock reads `end`; the first call first waits
  /// until the processes (attached: Conductor::wait_attached) are ready.
  /// ProcessStuck: see above.
  void run_until(Nanos end);
  Nanos now() const noexcept { return clock_.now(); }
  std::uint64_t physics_steps() const noexcept { return time_.steps(); }
  /// Frames the processes sent, as seen on the buses.
  std::uint64_t frames_from_processes() const noexcept { return from_processes_; }
  /// Every bus as a candump log in virtual time: by time, then robot, then arrival.
  std::string trace() const;
  /// The FTT and timing violations on robot r's bus so far (check_timing; else 0).
  std::uint64_t ftt_violations(std::size_t robot) const;
  /// BusWatch::trace_hash of the frames so far.
  std::uint64_t trace_hash() const noexcept;

  class Processes;  // the external processes as one participant
  class WireClock;  // the buses' driven wires as one participant

  /// Whether every robot's bus is on a timed wire in lockstep (the session's
  /// BusPhysics, on canhil's user-space bus: its broker's wire on this
  /// run's virtual clock).
  bool timed_wire() const noexcept { return timed_; }

 private:
  void observe();
  /// What is still on its way: empty once every frame sent so far has reached
  /// every socket (the observers and the fence agree).
  std::string in_flight(std::uint64_t sent);
  /// On a timed wire: frames the broker has taken onto the wire, and frames
  /// the wire delivered, on the run's buses since it began.
  std::uint64_t taken() const;
  std::uint64_t delivered() const;
  /// What the processes have on the buses: frames sent, or on a timed wire
  /// frames delivered (a frame sent is on the wire until its end of frame).
  std::uint64_t on_buses(std::uint64_t sent) const { return timed_ ? delivered() : sent; }
  /// The first robot whose observed frames the fence does not yet say are
  /// in every socket of its interface; none when every one's are.
  std::optional<std::size_t> unfenced();
  std::uint64_t canhil_sent() const;
  /// Lets the processes see this instant and waits until they are done with
  /// it; returns how many frames they sent since the last time.
  std::size_t settle();
  /// Wakes the agents whose frames the last step wrote (PMan ticks, canhil's
  /// RTDB's frame signal): called once the processes' clock reads the instant.
  void activate_agents();

  Session& session_;
  lockstep::Conductor& conductor_;
  ExternalOptions options_;
  can_nodes::SimulatedClock clock_;
  std::vector<std::vector<can_nodes::SocketCanBus*>> sockets_;       // per robot, per node
  can_nodes::DeliveryFence fence_;                                   // opened before any other socket
  std::vector<std::unique_ptr<can_nodes::SocketCanBus>> observers_;  // per robot
  std::vector<std::unique_ptr<can_nodes::SocketCanMedium>> media_;   // per distinct interface
  // The media this run gave a driven wire: instant again when the driver
  // goes, however it goes (a constructor that throws included).
  struct DrivenWires {
    std::vector<can_nodes::SocketCanMedium*> given;
    DrivenWires() = default;
    DrivenWires(const DrivenWires&) = delete;
    DrivenWires& operator=(const DrivenWires&) = delete;
    ~DrivenWires() { undo(); }
    void undo() {
      for (can_nodes::SocketCanMedium* m : given) m->set_wire(can_nodes::Wire{});
      given.clear();
    }
  } driven_;
  std::vector<std::uint64_t> taken0_, delivered0_;  // per medium: its counts when the run began
  bool timed_ = false;
  std::uint64_t wire_wanted_ = 0;      // in_flight() last waited for the broker to take this many frames
  std::uint64_t observed_frames_ = 0;  // observed_ less error frames (the wire's deliveries)
  std::unique_ptr<WireClock> wire_clock_;
  std::vector<std::uint64_t> fenced_;  // per robot: frames the observer saw that the fence tells about
  // epoll: readable when a frame reaches an observer or the kernel's fence (wait_quiet's ready_fd)
  int arrivals_ = -1;
  // On the user-space bus: whether a frame waits at an observer, or the fence
  // has what in_flight() last waited for, from the bus's counts (wait_quiet's arrived).
  std::function<bool()> arrived_;
  bool waiting_on_fence_ = false;  // in_flight() last waited for the fence
  BusWatch watch_;
  std::uint64_t observed_ = 0;
  std::uint64_t observed_at_settle_ = 0;
  std::uint64_t announced_ = 0;      // frames on the buses when the processes were last nudged
  std::uint32_t settled_epoch_ = 0;  // the epoch the processes were quiet at, at the last settle
  bool settled_once_ = false;
  bool started_ = false;
  std::uint64_t from_processes_ = 0;
  std::vector<bool> woken_;   // robots whose agents PMan activated at this instant
  std::vector<bool> cycled_;  // robots whose agents have ended a first activation
  std::unique_ptr<Processes> processes_;
  can_nodes::VirtualTime time_;
};

}  // namespace canhil::emulator
