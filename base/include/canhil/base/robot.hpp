// canhil/base/robot.hpp — the words the physics and the emulated nodes share
// about a robot, defined once: what became of a kick, and the battery packs'
// voltages. (Neither layer depends on the other.)
#pragma once

#include <cstdint>

namespace canhil {

/// What a kick command did.
enum class KickOutcome : std::uint8_t {
  kFired,       ///< the kicker fired
  kNotEngaged,  ///< the barrier did not see the ball in the control area
  kLowVoltage,  ///< the capacitor was below its firing voltage
  kNoPower,     ///< a power of 0 asks for nothing
};

/// The three packs' voltages, as the base node measures them.
struct BatteryVolts {
  double logic_v = 0;
  double power12_v = 0;
  double power24_v = 0;
  friend bool operator==(const BatteryVolts&, const BatteryVolts&) = default;
};

}  // namespace canhil
