// canhil/can_nodes/bus.hpp — the narrow interface every node talks through:
// an Endpoint, one controller's place on a bus (the medium: a MemoryBus, the
// kernel's SocketCAN, canhil's user-space bus).
//
// Two backends: SocketCanBus (a CAN_RAW socket on vcan or a real interface)
// and the endpoints of a MemoryBus (in-process, deterministic). Both are non-blocking:
// send() never waits for the wire, receive() returns nothing when nothing is
// there. An Endpoint is used from one thread at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "canhil/frames/frame.hpp"

namespace canhil::can_nodes {

class Doorbell;

using frames::CanFrame;
using frames::TimedFrame;

/// SocketCAN's receive filter: a frame passes when (frame.id & mask) == (id & mask),
/// with `extended` and `remote` compared when their *_mask flags are set
/// (CAN_EFF_FLAG / CAN_RTR_FLAG in the mask). `invert` passes the complement.
struct Filter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  bool extended = false;
  bool match_extended = false;  ///< compare the extended flag
  bool remote = false;
  bool match_remote = false;  ///< compare the remote flag
  bool invert = false;

  static Filter exact(std::uint32_t standard_id) {
    return Filter{standard_id, frames::kStandardIdMask, false, true, false, true, false};
  }
  static Filter all() { return Filter{}; }
  bool matches(const CanFrame& frame) const noexcept;
  /// matches() for a data frame with 11-bit identifier `id`, neither extended
  /// nor remote (what a bus routes by table).
  bool matches_standard_data(std::uint32_t standard_id) const noexcept { return hits(standard_id) != invert; }

 private:
  static constexpr std::uint32_t kEffFlag = 0x8000'0000u;  // CAN_EFF_FLAG
  static constexpr std::uint32_t kRtrFlag = 0x4000'0000u;  // CAN_RTR_FLAG
  // SocketCAN's test: the received id with its flags against the wanted one, under the mask.
  bool hits(std::uint32_t rx) const noexcept {
    const std::uint32_t want = id | (extended ? kEffFlag : 0u) | (remote ? kRtrFlag : 0u);
    const std::uint32_t m = mask | (match_extended ? kEffFlag : 0u) | (match_remote ? kRtrFlag : 0u);
    return (rx & m) == (want & m);
  }
};

enum class SendStatus : std::uint8_t {
  kOk,       ///< handed to the bus
  kDropped,  ///< the transmit queue stayed full through every retry; counted in stats
  kDown,     ///< the interface is down or gone; see Endpoint::state()
};

enum class BusState : std::uint8_t {
  kUp,
  kDown,  ///< interface administratively down or carrier lost; may come back
  kGone,  ///< interface removed; reopen it
};
/// "up", "down" or "gone", as the commands report it.
const char* state_name(BusState state) noexcept;

struct BusStats {
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t send_retries = 0;   ///< ENOBUFS/EAGAIN retries that later succeeded or not
  std::uint64_t send_dropped = 0;   ///< frames given up on after the last retry
  std::uint64_t rx_overflow = 0;    ///< frames the receive queue dropped (SO_RXQ_OVFL or memory queue)
  std::uint64_t errors = 0;         ///< error frames received
  std::uint64_t state_changes = 0;  ///< up/down transitions seen
};

class Endpoint {
 public:
  virtual ~Endpoint() = default;
  Endpoint(const Endpoint&) = delete;
  Endpoint& operator=(const Endpoint&) = delete;

  /// Sends one frame. Never blocks longer than the backend's bounded retry.
  virtual SendStatus send(const CanFrame& frame) = 0;
  /// The next received frame with its receive time, or nullopt when none waits.
  virtual std::optional<TimedFrame> receive() = 0;
  /// False only when receive() would certainly return nothing (a memory
  /// endpoint's empty queue); a socket may always have frames.
  virtual bool may_have_frames() const { return true; }
  /// Rings `bell` with `index` whenever a frame is queued for receive();
  /// nullptr stops it. The bus keeps its share of the bell. False when the backend cannot tell (a socket): then its
  /// reader must be asked (may_have_frames) instead.
  virtual bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) {
    (void)bell;
    (void)index;
    return false;
  }
  /// Replaces the receive filters; an empty list receives no data frames.
  virtual void set_filters(std::span<const Filter> filters) = 0;
  /// Which error-frame classes to receive (kErr*); 0, the default, receives none.
  virtual void set_error_mask(std::uint32_t mask) = 0;
  virtual BusState state() const = 0;
  virtual BusStats stats() const = 0;
  /// Name for logs and traces (the interface name, or the memory endpoint's name).
  virtual const std::string& name() const = 0;

 protected:
  Endpoint() = default;
};

}  // namespace canhil::can_nodes
