// canhil/emulator/session_options.hpp — what a run needs beyond its
// scenario, chosen by the command, not the file (part of a RunPlan).
#pragma once

#include "canhil/can_nodes/medium.hpp"

#include <memory>
#include <optional>

#include "canhil/base/time.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/runner.hpp"

namespace canhil::emulator {

/// The robots' buses as the run has them (plan_run resolves them from [bus],
/// --bit-rate and the message set; docs/wire.md).
struct BusPhysics {
  std::uint32_t bit_rate = 0;       ///< the wire's bit/s; 0: instant (no wire time, no errors)
  std::uint32_t data_bit_rate = 0;  ///< CAN FD's data phase; 0: the bit rate
  std::optional<Nanos> restart = std::chrono::milliseconds(100);  ///< bus-off to restart; nullopt: on request
  std::size_t tx_queue = 10;                                      ///< frames a controller queues (can-dev's txqueuelen)
  /// Who chose the bit rate (plan_run), for the run's first lines.
  enum class From : std::uint8_t { kDefault, kFlag, kScenario, kDbc, kSocketCan, kNoBaudrate };
  From from = From::kDefault;
  /// `from` in words: "--bit-rate", "the scenario's [bus] bit_rate", "the DBC's Baudrate", ...
  const char* source() const noexcept {
    switch (from) {
      case From::kFlag:
        return "--bit-rate";
      case From::kScenario:
        return "the scenario's [bus] bit_rate";
      case From::kDbc:
        return "the DBC's Baudrate";
      case From::kSocketCan:
        return "on SocketCAN the DBC's Baudrate alone times nothing";
      case From::kNoBaudrate:
        return "no Baudrate in the DBC";
      case From::kDefault:
        break;
    }
    return "canhil's default";
  }
  bool timed() const noexcept { return bit_rate != 0; }
  /// As a medium's wire (can_nodes::Wire), its faults drawn from `seed`.
  can_nodes::Wire wire(std::uint64_t seed) const {
    can_nodes::Wire w;
    w.bit_rate = bit_rate;
    w.data_bit_rate = data_bit_rate;
    w.seed = seed;
    w.controller.queue_frames = tx_queue;
    w.controller.restart_delay = restart;
    return w;
  }
};

/// What a run needs beyond its scenario: chosen by the command, not the file.
struct SessionOptions {
  std::shared_ptr<const frames::MessageSet> messages;
  frames::FttConfig ftt;  ///< EC, bit rate (for wire times and error frames), what stamps mark
  BusPhysics bus;         ///< the wire (plan_run: with a bit rate, ftt.stamps at the end of frame)
  vision_emu::VisionParams vision;
  bool vision_on = true;  ///< off: no vision and no RTDB (canhil nodes)
  /// The run follows the wall clock, so processes outside it can take part
  /// (the laptop side's defaults: PMan masters only then, see resolve_laptop).
  bool realtime = false;
  /// Processes outside take part in virtual time (ExternalDriver): the
  /// laptop side's defaults are those of a real-time run.
  bool external = false;
  Nanos world_log_period{0};  ///< 0: no world log
  /// Each world step, and the vision after it, timed in the stepping
  /// thread's CPU time (Session::step_timing), for `canhil bench --part
  /// match`: four clock reads a step.
  bool time_steps = false;
  /// A saved world (physics::load_state) to start from instead of the placements.
  std::optional<physics::WorldState> initial_state;
};

}  // namespace canhil::emulator
