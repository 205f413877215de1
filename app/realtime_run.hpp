// app/realtime_run.hpp — `canhil run` in real time (see realtime_run.cpp).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "canhil/emulator/scenario.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/physics/world.hpp"
#include "canhil/vision_emu/vision.hpp"

namespace canhil::app {

struct RealtimeOptions {
  std::shared_ptr<const frames::MessageSet> messages;
  vision_emu::VisionParams vision;
  double duration_s = 0;  ///< 0: until Ctrl-C
  std::uint32_t bit_rate = 1'000'000;
  /// Each node socket's receive buffer (SO_RCVBUFFORCE as root): room for a
  /// burst of other traffic while the emulator is busy; overflow is counted.
  int receive_buffer_bytes = 1 << 20;
  /// SCHED_FIFO priority of the thread that runs the nodes (1..99; 0 leaves
  /// the scheduler alone). Needs root or CAP_SYS_NICE; without, a warning.
  int priority = 40;
  std::optional<physics::WorldState> initial_state;  ///< a saved world to start from
  std::optional<std::string> save_world;             ///< where to save the world at the end
  bool quiet = false;                                ///< no progress lines
  bool silent = false;                               ///< nothing at all (a benchmark runs it)
};

/// Runs until the duration ends or Ctrl-C; returns the exit status (130 after Ctrl-C).
int run_realtime(const emulator::Scenario& scenario, const RealtimeOptions& options);

}  // namespace canhil::app
