// canhil/emulator/realtime_driver.hpp — a session in real time: every
// robot's emulated nodes on its SocketCAN interface (one socket per node, as
// separate microcontrollers), the physics locked to the wall clock, vision
// into each robot's agent's RTDB followed by DB_signal_frame.
//
// Three threads: the FTT masters on their own, one SCHED_FIFO priority above
// the other nodes, so a trigger message goes out at its EC boundary whatever
// the slaves are busy with (on a robot the master is a microcontroller of its
// own too); the other nodes on the caller's thread (run_until), SCHED_FIFO at
// `priority`; the physics with the vision on a third at normal priority
// (RealtimePhysics), exchanging commands and sensors through SharedRobotIo.
// Neither a physics step nor the slaves' work delays a trigger message.
#pragma once

#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "canhil/can_nodes/medium.hpp"
#include "canhil/can_nodes/realtime.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/realtime_physics.hpp"
#include "canhil/emulator/session.hpp"
#include "canhil/emulator/wall_waiter.hpp"

namespace canhil::emulator {

struct RealtimeOptions {
  /// Each node socket's receive buffer (SO_RCVBUFFORCE as root): room for a
  /// burst of other traffic while the emulator is busy; overflow is counted.
  int receive_buffer_bytes = 1 << 20;
  /// SCHED_FIFO priority of the node loop (the masters run one above); 0
  /// leaves the scheduler alone. Needs root or CAP_SYS_NICE; without, a warning.
  int priority = 40;
  /// Behind by more than this, the physics skips steps instead of a burst.
  Nanos max_behind = std::chrono::milliseconds(100);
};

class RealtimeDriver {
 public:
  /// Opens one socket per node on each robot's interface and builds the nodes,
  /// starting on a whole EC a little ahead. SetupError: no such interface, an
  /// interface down, error-frame faults on a CAN adapter, a schedule that
  /// does not fit. `session` must outlive the driver.
  RealtimeDriver(Session& session, RealtimeOptions options = {});
  ~RealtimeDriver();
  RealtimeDriver(const RealtimeDriver&) = delete;
  RealtimeDriver& operator=(const RealtimeDriver&) = delete;

  /// The wall-clock time the run starts at (its first EC); rule times count from here.
  Nanos start_time() const noexcept { return start_; }
  const can_nodes::WallClock& clock() const noexcept { return clock_; }

  /// Starts the physics and the masters' threads (once).
  void start();
  /// Runs the other nodes on this thread until the wall clock reads `end` or
  /// `stop` is set; call it again to go on (report in between).
  void run_until(Nanos end, const std::atomic<bool>& stop);
  /// Stops and joins the threads, then reads what is still queued on the
  /// sockets (bounded), so the counts cover every frame that reached the nodes.
  void stop();

  /// Interfaces whose state changed since the last call: (robot, new state).
  std::vector<std::pair<std::size_t, can_nodes::BusState>> bus_state_changes();
  RealtimeStats physics_stats() const { return physics_.stats(); }
  /// Whether robot r's bus carries the run's timed wire (the session's
  /// BusPhysics): on canhil's user-space bus, whose broker runs it, it does
  /// for the run (the interface is instant again after it); the kernel's
  /// vcan and adapters keep their own timing.
  bool timed_wire(std::size_t robot) const { return wired_.at(robot) != 0; }
  /// The medium of robot r's bus (its kind, its counts).
  const can_nodes::SocketCanMedium& medium(std::size_t robot) const { return *media_.at(robot); }
  /// Why the node loop could not get its SCHED_FIFO priority (empty: it did).
  const std::string& priority_problem() const noexcept { return priority_problem_; }
  /// Robot r's socket for node i (in can_nodes::NodeId order; kNodeCount: the
  /// system monitor's watching one); std::out_of_range for a real board's.
  const can_nodes::SocketCanBus& socket(std::size_t robot, std::size_t node) const {
    const can_nodes::SocketCanBus* s = sockets_.at(robot).at(node);
    if (s == nullptr) throw std::out_of_range("no socket: that node is a real board's");
    return *s;
  }

 private:
  Session& session_;
  RealtimeOptions options_;
  can_nodes::WallClock clock_;
  Nanos start_{0};
  std::vector<std::unique_ptr<can_nodes::SocketCanMedium>> media_;  // per robot
  std::vector<std::uint8_t> wired_;  // per robot: its medium carries the run's timed wire (set here, undone at the end)
  std::vector<std::vector<can_nodes::SocketCanBus*>> sockets_;  // [robot][NodeId, watch]; null: not emulated
  std::vector<can_nodes::SocketCanBus*> watched_;               // per robot, the socket whose state is read
  std::vector<can_nodes::BusState> states_;
  std::unique_ptr<WallWaiter> waiter_;
  std::unique_ptr<can_nodes::Realtime> loop_;     // every node but the masters
  std::unique_ptr<can_nodes::Realtime> masters_;  // the FTT masters
  RealtimePhysics physics_;
  std::atomic<bool> masters_stop_{false};
  std::thread masters_thread_;
  bool started_ = false, stopped_ = false;
  std::string priority_problem_;
  struct Locked;
  std::unique_ptr<Locked> memory_;  // the process's memory locked while running
};

}  // namespace canhil::emulator
