// The broker's timed interfaces: one wire model (wire::WireBus) per interface
// whose bit rate is set, run in real time on the broker's monotonic clock.
// Each process with a socket bound to a timed interface (or to every one) is
// one controller there, as one adapter in one machine: its sockets share the
// controller's transmit queue, which the preload keeps at the interface's
// tx_queue (ENOBUFS past it, Controller::queued). What the wire says
// happened (a frame's end of frame, a controller's error report) goes back to
// the broker as a WireDelivery, which routes it to the sockets.
#pragma once

#include <linux/can.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace canhil::userbus {

struct State;
struct Controller;
struct TxRecord;
struct FaultRequest;
struct ControlRequest;

/// A controller on a timed interface: a process's (slot -1), or one socket's own (kOwnController).
struct ControllerKey {
  std::int32_t pid = 0;
  std::int32_t slot = -1;
  friend bool operator==(const ControllerKey&, const ControllerKey&) = default;
};

/// A frame at its end of frame, or a controller's error frame.
struct WireDelivery {
  bool error = false;
  std::int32_t ifindex = 0;
  ControllerKey from;      ///< frame: the sender (pid 0: a fault's babbling); error: the reporter
  std::uint64_t tag = 0;   ///< frame: the sending connection (submit's tag); 0 for a babbling fault's
  std::int64_t at_ns = 0;  ///< monotonic: its last bit, or when the error was seen
  std::uint32_t size = 0;  ///< CAN_MTU or CANFD_MTU
  unsigned char frame[CANFD_MTU] = {};
  std::vector<ControllerKey> missed;  ///< frame: controllers that did not receive it (bus-off, cut off)
};

class BrokerWire {
 public:
  explicit BrokerWire(State& state);
  ~BrokerWire();
  BrokerWire(const BrokerWire&) = delete;
  BrokerWire& operator=(const BrokerWire&) = delete;

  /// Takes the interfaces' wire settings as they stand now: a wire begins
  /// where a bit rate was set, ends where it went to 0 or its interface
  /// went away (its waiting frames with it), restarts with new rates.
  void sync(std::int64_t now);
  bool timed(std::int32_t ifindex) const noexcept;
  /// A socket on timed interface `ifindex`: its controller `key` there.
  void join(ControllerKey key, std::int32_t ifindex);
  /// Controller `key` has no socket any more: it leaves its buses once it
  /// has sent what it holds.
  void leave(ControllerKey key);
  /// A frame given on a timed interface by connection `tag`, of controller
  /// `key`; on a driven wire at the record's time (what the wire did up to
  /// then appended to `out`).
  void submit(ControllerKey key, std::uint64_t tag, const TxRecord& record, std::int64_t now,
              std::vector<WireDelivery>& out);
  /// A frame controller `key` counted into its queue on `ifindex` that the
  /// broker dropped before the wire (its interface down): counted out again.
  void refund(ControllerKey key, std::int32_t ifindex);
  /// When advance() next has something to do (monotonic ns); INT64_MAX: nothing.
  std::int64_t next_due() const noexcept;
  /// Runs every wire up to `now`, appending what happened, in order of time per interface.
  void advance(std::int64_t now, std::vector<WireDelivery>& out);
  /// A driven wire (Interface::driven: a lockstep run's clock) run to its
  /// own time `time_ns`; its deliveries' at_ns are in that time.
  void drive(std::int32_t ifindex, std::int64_t time_ns, std::vector<WireDelivery>& out);

  /// A control request about a timed interface (restart, fault, clear, a
  /// driven wire's time): its answer, 0 or -errno (-EINVAL: not one of
  /// those); what a driven wire delivered appended to `out`.
  int control(const ControlRequest& request, std::int64_t now, std::vector<WireDelivery>& out);
  /// `canhil bus link IFACE restart`: the bus-off controllers of `pid` (0: all) on `ifindex`; 0 or -errno.
  int restart(std::int32_t ifindex, std::int32_t pid, std::int64_t now);
  int add_fault(std::int32_t ifindex, const FaultRequest& fault, std::int64_t now);
  int clear_faults(std::int32_t ifindex, std::int64_t now);

 private:
  struct Wire;
  Wire* wire_of(std::int32_t ifindex) const noexcept;
  void publish(Wire& w, std::int64_t now);
  void publish_due(Wire& w);
  void collect(Wire& w, std::int64_t now, std::vector<WireDelivery>& out);
  void retire(Wire& w);
  void release(Wire& w, ControllerKey key, std::uint32_t n);
  Controller* row(ControllerKey key, std::int32_t ifindex, bool claim);
  void account_losses(Wire& w);
  static std::size_t live_members(const Wire& w);

  State& state_;
  std::vector<std::unique_ptr<Wire>> wires_;  // by interface slot
};

}  // namespace canhil::userbus
