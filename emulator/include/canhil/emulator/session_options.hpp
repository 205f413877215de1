// canhil/emulator/session_options.hpp — what a run needs beyond its
// scenario, chosen by the command, not the file (part of a RunPlan).
#pragma once

#include <memory>
#include <optional>

#include "canhil/base/time.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/runner.hpp"

namespace canhil::emulator {

/// What a run needs beyond its scenario: chosen by the command, not the file.
struct SessionOptions {
  std::shared_ptr<const frames::MessageSet> messages;
  frames::FttConfig ftt;  ///< EC, bit rate (for wire times and error frames)
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
