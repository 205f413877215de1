// canhil/external/time_shim.hpp — canhil itself under the time shim: a run
// with the team's processes needs canhil's own clocks and waits to follow the
// lockstep board as theirs do, so canhil preloads the shim into itself by
// starting itself again once (canhil/base/start_again.hpp), and hands the
// team's processes the preload it was first given.
#pragma once

#include <string>

namespace canhil::external {

/// The time shim's path: $CANHIL_TIMESHIM, next to an installed canhil, or
/// the build tree's. SetupError naming the places looked at.
std::string find_timeshim();

/// Makes sure canhil's own clocks can follow the lockstep board: when the shim
/// is not preloaded yet, starts canhil again (same arguments) with it; the
/// process then goes on with the team's LD_PRELOAD restored for what it
/// starts. Returns the preload the team's processes should keep after the shim
/// (LD_PRELOAD as canhil was first given it). SetupError when it cannot.
std::string preload_shim_into_self(const std::string& shim);

}  // namespace canhil::external
