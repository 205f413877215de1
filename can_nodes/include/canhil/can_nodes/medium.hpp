// canhil/can_nodes/medium.hpp — what canhil needs of a bus medium, declared
// once. A medium carries one bus's frames between its controllers; canhil
// has three:
//
//   kMemory     a MemoryBus: in this process, in virtual time, deterministic
//   kKernel     the kernel's SocketCAN: a vcan, or a real adapter (can0)
//   kUserSpace  canhil's user-space bus (libcanhil-bus.so and its broker)
//
// and asks each the same things: a controller's place on it (open: an
// Endpoint, what nodes, handlers and observers send and receive through),
// whether it can carry a timed wire (set_wire: canhil's wire model, which the
// memory bus and the user-space bus's broker run; the kernel's own timing
// holds on a vcan or an adapter), and what it has carried (counts). When a
// frame has reached every receiver is DeliveryFence's, which asks kind().
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "canhil/can_nodes/bus.hpp"
#include "canhil/wire/wire_bus.hpp"

namespace canhil::can_nodes {

struct SocketCanOptions;
class SocketCanBus;

enum class MediumKind : std::uint8_t { kMemory, kKernel, kUserSpace };
/// "canhil's in-memory bus", "the kernel's SocketCAN", "canhil's user-space bus".
const char* medium_name(MediumKind kind) noexcept;

/// A bit-timed wire: its bit rate (0: none, frames delivered at once),
/// whether a frame takes its exact bits or the worst case of its shape, and
/// what its time stamp says: its end of frame (a controller's receive stamp)
/// or its first bit (a controller's start-of-frame stamp, and what canhil's
/// FTT slaves take a TM's stamp to be: frames/ftt_slot.hpp). Either way a
/// frame is delivered when its end of frame has passed. The rest as
/// wire::WireConfig and wire::ControllerOptions, for every controller.
struct Wire {
  enum class Bits : std::uint8_t { kExact, kWorstCase };
  enum class Stamp : std::uint8_t { kEndOfFrame, kStartOfFrame };
  std::uint32_t bit_rate = 0;
  Bits bits = Bits::kExact;
  Stamp stamp = Stamp::kEndOfFrame;
  std::uint32_t data_bit_rate = 0;
  std::uint64_t seed = 1;
  wire::ControllerOptions controller{};
  /// Its clock is the caller's, moved by SocketCanMedium::drive (a lockstep
  /// run's virtual time), not the medium's own (the user-space bus only).
  bool driven = false;
};

/// What a medium has carried.
struct MediumCounts {
  std::uint64_t frames = 0;        ///< frames carried
  std::uint64_t error_frames = 0;  ///< errors on its wire
  double load = 0;                 ///< the share of time its wire carried bits; 0 without a wire
  bool timed = false;              ///< it has a wire
  std::uint64_t delivered = 0;     ///< frames its wire delivered whole
  Nanos next_event = kNever;       ///< a driven wire's next event, in its time
};

class Medium {
 public:
  virtual ~Medium() = default;
  virtual MediumKind kind() const noexcept = 0;
  /// A controller's place on the medium, called `name` (an emulated node,
  /// the handler, an observer): one controller of its own on a timed wire.
  virtual std::unique_ptr<Endpoint> open(const std::string& name) = 0;
  /// Gives the medium a wire (`wire.bit_rate` 0: instant again); false, and
  /// nothing changed, where it cannot carry canhil's (the kernel's).
  virtual bool set_wire(const Wire& wire) = 0;
  virtual MediumCounts counts() const = 0;
};

/// Which medium serves SocketCAN interface `iface` in this process:
/// kUserSpace when this process runs on canhil's user-space bus (its preload
/// loaded) and the bus has `iface`, else kKernel.
MediumKind socketcan_medium_kind(const std::string& iface) noexcept;

/// SocketCAN interface `iface` as this process reaches it: canhil's
/// user-space bus when this process runs on it and the bus has `iface`,
/// else the kernel's. Its endpoints are opened with `options`.
class SocketCanMedium final : public Medium {
 public:
  explicit SocketCanMedium(std::string iface);
  SocketCanMedium(std::string iface, const SocketCanOptions& options);
  ~SocketCanMedium() override;
  MediumKind kind() const noexcept override;
  std::unique_ptr<Endpoint> open(const std::string& name) override;
  /// open(), as the socket it is (for poll and the kernel's counters).
  std::unique_ptr<SocketCanBus> open_socket();
  /// The user-space bus only (its broker runs the wire, in real time, or
  /// on the caller's clock when `wire.driven`).
  bool set_wire(const Wire& wire) override;
  /// A driven wire run to `now` (its time): what it delivers by then is in
  /// the sockets when this returns.
  void drive(Nanos now);
  MediumCounts counts() const override;
  const std::string& interface() const noexcept { return iface_; }

 private:
  std::string iface_;
  std::unique_ptr<SocketCanOptions> options_;
};

}  // namespace canhil::can_nodes
