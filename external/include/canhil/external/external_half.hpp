// canhil/external/external_half.hpp — `canhil match --external`: each half
// of a match played by the teams' own processes in lockstep, an ExternalRun
// per half, started afresh from the half's plan ([teams.external], else
// [external], the second team's with SECOND_RTDB=1) and stopped when the
// half ends.
#pragma once

#include <optional>
#include <string>

#include "canhil/emulator/match.hpp"

namespace canhil::external {

struct ExternalMatch {
  std::string shim;          ///< the time shim (find_timeshim)
  std::string team_preload;  ///< what the team's processes keep preloaded after it
  /// Each process's output in its own file here (match<k>-half<h>-TEAM-agent<N>-PROGRAM.log);
  /// none: on canhil's stderr (its stdout is the table, or JSON).
  std::optional<std::string> logs;
  int* match = nullptr;  ///< the number of the match being played (1, 2, ...), for the logs' names
  /// One match at a time: the bus's broker may spin (spin_the_bus). Not for
  /// --jobs 2 and more, whose workers would take each other's cores.
  bool alone = false;
};

/// The halves' drivers. A process that does not attach within the scenario's
/// attach_limit_s, or stops answering, ends the match with
/// emulator::ProcessStuck naming the match, the half and the process.
emulator::HalfDriverMaker external_halves(const ExternalMatch& how);

}  // namespace canhil::external
