// The owner of a run with the team's own processes (external_run.hpp).
#include "canhil/external/external_run.hpp"

#include <cstdio>

#include "canhil/base/text_format.hpp"

namespace canhil::external {
namespace {

emulator::ExternalOptions driver_options(const emulator::Session& session, const ExternalSetup& setup) {
  emulator::ExternalOptions o;
  o.start_limit = from_seconds(session.plan().external.attach_limit_s);
  o.record_trace = setup.record_trace;
  o.check_timing = setup.check_timing;
  return o;
}

}  // namespace

ExternalRun::ExternalRun(emulator::Session& session, ExternalSetup setup)
    : session_(session),
      setup_(std::move(setup)),
      conductor_(session.plan().external.conductor),
      driver_(session, conductor_, driver_options(session, setup_)),
      processes_(
          conductor_.environment(setup_.shim, setup_.team_preload.empty() ? nullptr : setup_.team_preload.c_str()),
          setup_.say, setup_.output),
      spin_(setup_.spin_bus ? spin_the_bus(session) : nullptr) {}

ExternalRun::~ExternalRun() { stop(); }

std::string ExternalRun::named(const char* joint, const std::string& what) const {
  return setup_.name.empty() ? what : setup_.name + joint + what;
}

void ExternalRun::start() {
  const emulator::ExternalPlan& plan = session_.plan().external;
  if (!plan.launches.empty()) {
    expected_ = processes_.start_all(session_);
  } else {
    expected_ = setup_.wait_for > 0 ? setup_.wait_for : 2 * session_.robot_count();
    std::fprintf(setup_.say, "  start your handler and agent (AGENT=N) with:\n   ");
    for (const std::string& e : processes_.environment()) std::fprintf(setup_.say, " %s", e.c_str());
    if (plan.syslog == "system") std::fprintf(setup_.say, " CANHIL_SYSLOG=system");
    std::fprintf(setup_.say, "\n  waiting for %zu process(es), %g s at most\n", expected_, plan.attach_limit_s);
  }
  std::fflush(setup_.say);
  const std::size_t attached = conductor_.wait_attached(expected_, from_seconds(plan.attach_limit_s));
  if (attached < expected_) {
    stop();
    throw emulator::ProcessStuck(named(
        ": ", std::to_string(attached) + " of " + std::to_string(expected_) + " process(es) attached within " +
                  format_text("%g", plan.attach_limit_s) + " s (attach_limit_s in [external] or [teams.external])"));
  }
}

void ExternalRun::run_until(Nanos end) {
  try {
    driver_.run_until(end);
  } catch (const emulator::ProcessStuck& e) {
    throw emulator::ProcessStuck(named(" ", format_text("at t = %.3f s: ", to_seconds(driver_.now())) + e.what()));
  }
  processes_.reap(driver_.now());
  if (const std::string why = processes_.not_started(); !why.empty()) {
    throw emulator::ProcessStuck(named(" ", format_text("at t = %.3f s: ", to_seconds(driver_.now())) + why));
  }
}

void ExternalRun::stop() {
  if (stopped_) return;
  stopped_ = true;
  conductor_.release();  // the run is over: their waits end, they take their SIGINT
  processes_.stop_all();
}

}  // namespace canhil::external
