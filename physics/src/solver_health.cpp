#include "canhil/physics/solver_health.hpp"

#include "canhil/base/text_format.hpp"

#include <ode/ode.h>

#include <cstdarg>
#include <cstdio>
#include <mutex>
#include <utility>

#include "solver_scope.hpp"

namespace canhil::physics {

const char* solver_report_kind_name(SolverReportKind kind) noexcept {
  switch (kind) {
    case SolverReportKind::kMessage:
      return "message";
    case SolverReportKind::kInternalError:
      return "internal error";
    case SolverReportKind::kError:
      return "error";
  }
  return "report";
}

void SolverHealth::add(SolverReport report) {
  switch (report.kind) {
    case SolverReportKind::kMessage:
      ++messages;
      break;
    case SolverReportKind::kInternalError:
      ++internal_errors;
      break;
    case SolverReportKind::kError:
      ++errors;
      break;
  }
  if (first.size() < kKept) first.push_back(std::move(report));
}

void SolverHealth::add(const SolverHealth& other) {
  messages += other.messages;
  internal_errors += other.internal_errors;
  errors += other.errors;
  for (const SolverReport& r : other.first) {
    if (first.size() >= kKept) break;
    first.push_back(r);
  }
}

std::string SolverHealth::summary() const {
  char head[160];
  std::snprintf(head, sizeof head, "%llu solver message(s), %llu internal error(s), %llu error(s)",
                static_cast<unsigned long long>(messages), static_cast<unsigned long long>(internal_errors),
                static_cast<unsigned long long>(errors));
  std::string out = head;
  if (!first.empty()) {
    char at[64];
    std::snprintf(at, sizeof at, " (first at t = %.3f s: ", first.front().time_s);
    out += at + first.front().text + ")";
  }
  return out;
}

std::string SolverHealth::describe(const std::string& indent) const {
  std::string out = indent + "physics: " + summary() + "\n";
  for (const SolverReport& r : first) {
    char head[96];
    std::snprintf(head, sizeof head, "  t = %.3f s  ODE %s %d: ", r.time_s, solver_report_kind_name(r.kind), r.code);
    out += indent + head + r.text + "\n";
  }
  return out;
}

namespace {

std::string formatted(const SolverReport& r) {
  char at[96];
  std::snprintf(at, sizeof at, "ODE %s %d at t = %.3f s: ", solver_report_kind_name(r.kind), r.code, r.time_s);
  return at + r.text;
}

}  // namespace

SolverError::SolverError(const SolverReport& report) : std::runtime_error(formatted(report)), report_(report) {}

namespace detail {

struct ScopeAccess {
  static SolverHealth& health(SolverScope& s) { return s.health_; }
  static double time(const SolverScope& s) { return s.time_s_; }
};

namespace {

thread_local SolverScope* t_current = nullptr;

void report(SolverReportKind kind, int code, const char* format, va_list ap) {
  SolverReport r;
  r.kind = kind;
  r.code = code;
  r.text = vformat_text(format, ap);
  if (t_current != nullptr) {
    r.time_s = ScopeAccess::time(*t_current);
    ScopeAccess::health(*t_current).add(r);
  } else if (kind == SolverReportKind::kMessage) {
    std::fprintf(stderr, "ODE Message %d: %s\n", code, r.text.c_str());
  }
  // ODE exits or aborts when an error handler returns: the call unwinds instead.
  if (kind != SolverReportKind::kMessage) throw SolverError(r);
}

void on_message(int code, const char* format, va_list ap) { report(SolverReportKind::kMessage, code, format, ap); }
void on_debug(int code, const char* format, va_list ap) { report(SolverReportKind::kInternalError, code, format, ap); }
void on_error(int code, const char* format, va_list ap) { report(SolverReportKind::kError, code, format, ap); }

}  // namespace

void install_solver_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    dSetMessageHandler(on_message);
    dSetDebugHandler(on_debug);
    dSetErrorHandler(on_error);
  });
}

SolverScope::SolverScope(SolverHealth& health, const double& time_s) noexcept
    : health_(health), time_s_(time_s), outer_(t_current) {
  install_solver_handlers();  // a scope without a World first (a test) is routed too
  t_current = this;
}

SolverScope::~SolverScope() { t_current = outer_; }

}  // namespace detail
}  // namespace canhil::physics
