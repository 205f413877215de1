// canhil/external/worker.hpp — what one worker of `canhil match --external
// --jobs N` keeps to itself, so that matches with the teams' own processes run
// side by side on one machine: a System V IPC namespace of its own (a team's
// RTDB and PMan take fixed keys) and a user-space CAN bus of its own with the
// scenario's interfaces (every match names the robots' interfaces the same).
#pragma once

#include <string>
#include <vector>

#include "canhil/userbus/bus.hpp"

namespace canhil::external {

/// Before the workers are forked: removes the buses of workers that were
/// killed (their folders, `<folder>-worker-<pid>`, the pid gone), and makes
/// sure canhil's own sockets, and the teams' processes', can go to a bus of a
/// worker's own: the bus's preload is put in LD_PRELOAD, for the start again
/// that preload_shim_into_self makes (when canhil is not on the user-space bus
/// already). SetupError when the preload cannot be found.
void prepare_external_workers();

class ExternalWorker {
 public:
  /// In a freshly forked worker (one thread): enters an IPC namespace of its
  /// own, starts a bus of its own beside the current one's folder
  /// (`<folder>-worker-<pid>`) with `interfaces` up, and points CANHIL_BUS_DIR
  /// at it for canhil's sockets and the processes it starts. SetupError when
  /// either cannot be made.
  explicit ExternalWorker(const std::vector<std::string>& interfaces);
  /// Stops the bus and removes its folder.
  ~ExternalWorker();
  /// Before each match: a fresh IPC namespace, so that what a team's
  /// processes left in the last match (a segment, a semaphore) is not there.
  static void next_match();
  ExternalWorker(const ExternalWorker&) = delete;
  ExternalWorker& operator=(const ExternalWorker&) = delete;

 private:
  userbus::BusPaths paths_;
};

}  // namespace canhil::external
