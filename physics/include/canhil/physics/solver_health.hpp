// canhil/physics/solver_health.hpp — what ODE itself says while it simulates.
//
// ODE reports through three process-wide handlers: messages (it goes on, e.g.
// "LCP internal error, s <= 0"), internal errors (a failed assertion: its
// debug handler) and errors. Left alone it prints them to stderr and, for the
// last two, aborts or exits the process. canhil installs its own handlers
// (physics::World does, before its first ODE call): each report is counted in
// the SolverHealth of the world being built or stepped on that thread, with
// the simulation time it came at (the first kKept kept whole); an internal
// error or an error then throws SolverError out of the World call, so a run
// stops with a message that names ODE's report instead of aborting.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace canhil::physics {

enum class SolverReportKind : std::uint8_t { kMessage, kInternalError, kError };

/// "message", "internal error", "error".
const char* solver_report_kind_name(SolverReportKind kind) noexcept;

/// One of ODE's reports.
struct SolverReport {
  SolverReportKind kind = SolverReportKind::kMessage;
  int code = 0;       ///< ODE's number (d_ERR_IASSERT, d_ERR_UASSERT, d_ERR_LCP, ...)
  double time_s = 0;  ///< the world's simulation time when ODE said it
  std::string text;   ///< ODE's text, formatted
};

/// A world's (or a run's, or a match's) count of ODE's reports.
struct SolverHealth {
  static constexpr std::size_t kKept = 5;
  std::uint64_t messages = 0;
  std::uint64_t internal_errors = 0;
  std::uint64_t errors = 0;
  std::vector<SolverReport> first;  ///< the first kKept reports, oldest first

  std::uint64_t total() const noexcept { return messages + internal_errors + errors; }
  /// Counts one report (and keeps it while fewer than kKept are).
  void add(SolverReport report);
  /// Adds another's counts; its kept reports fill what is left of kKept.
  void add(const SolverHealth& other);
  /// "0 solver messages" or "3 solver messages (first at t = 1.230 s: LCP internal error, s <= 0)":
  /// one line for a summary.
  std::string summary() const;
  /// For a run's summary: "<indent>physics: " + summary(), then each kept
  /// report on a line of its own ("<indent>  t = 1.230 s  ODE message 2: ..."),
  /// every line ending in a newline.
  std::string describe(const std::string& indent) const;
};

/// ODE stopped with an error or an internal error: the simulation cannot go
/// on. what(): "ODE internal error 1 at t = 0.000 s: assertion ... failed in dBodySetMass()".
class SolverError : public std::runtime_error {
 public:
  explicit SolverError(const SolverReport& report);
  const SolverReport& report() const noexcept { return report_; }

 private:
  SolverReport report_;
};

}  // namespace canhil::physics
