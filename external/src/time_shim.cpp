// canhil under the time shim (time_shim.hpp).
#include "canhil/external/time_shim.hpp"

#include <cstdlib>
#include <filesystem>

#include "canhil/base/assets.hpp"
#include "canhil/base/errno_text.hpp"
#include "canhil/base/preload.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/base/start_again.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/lockstep/shim_hook.h"

namespace canhil::external {
namespace {

constexpr const char* kRestartedVariable = "CANHIL_TIMESHIM_RESTARTED";
constexpr const char* kTeamPreloadVariable = "CANHIL_TEAM_PRELOAD";

}  // namespace

std::string find_timeshim() {
  return find_asset("CANHIL_TIMESHIM", "the time shim",
                    {std::filesystem::path("..") / CANHIL_INSTALL_LIBDIR / "libcanhil-timeshim.so"},
                    CANHIL_BUILD_TIMESHIM, "canhil_timeshim")
      .string();
}

std::string preload_shim_into_self(const std::string& shim) {
  if (preload::any_symbol<canhil_timeshim_conduct_fn>(CANHIL_TIMESHIM_CONDUCT) != nullptr) {
    // Started again with the shim: the team's processes get the preload canhil was first given.
    const char* team = std::getenv(kTeamPreloadVariable);
    std::string given = team != nullptr ? team : "";
    if (given.empty()) {
      unsetenv("LD_PRELOAD");
    } else {
      setenv("LD_PRELOAD", given.c_str(), 1);
    }
    unsetenv(kTeamPreloadVariable);
    unsetenv(kRestartedVariable);
    return given;
  }
  if (std::getenv(kRestartedVariable) != nullptr) {
    throw SetupError("canhil started itself again with LD_PRELOAD=" + shim +
                     " and the shim is still not loaded: is it a library for this machine? (`ldd " + shim + "`)");
  }
  setenv(kTeamPreloadVariable, current_preload().c_str(), 1);
  setenv(kRestartedVariable, "1", 1);
  preload_first(shim);
  // The keys this image claimed: the one started next claims its own (a claim
  // kept across the exec had no owner to give it back, until the next run).
  release_private_rtdb_keys();
  const int err = start_again();
  throw SetupError("canhil could not start itself again with the time shim: " + errno_text(err));
}

}  // namespace canhil::external
