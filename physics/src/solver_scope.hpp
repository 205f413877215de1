// solver_scope.hpp — which world ODE's reports on this thread belong to
// (physics/src; World uses it around everything that calls ODE).
#pragma once

#include "canhil/physics/solver_health.hpp"

namespace canhil::physics::detail {

/// Installs canhil's handlers in ODE (the first call in a process; World and
/// SolverScope call it).
void install_solver_handlers();

/// While one lives, ODE's reports on this thread go to `health`, stamped with
/// `*time_s`. Nested scopes stack (the innermost is current). Outside every
/// scope a message goes to stderr as ODE printed it, and an error or internal
/// error still throws SolverError.
class SolverScope {
 public:
  SolverScope(SolverHealth& health, const double& time_s) noexcept;
  ~SolverScope();
  SolverScope(const SolverScope&) = delete;
  SolverScope& operator=(const SolverScope&) = delete;

 private:
  SolverHealth& health_;
  const double& time_s_;
  SolverScope* outer_;
  friend struct ScopeAccess;
};

}  // namespace canhil::physics::detail
