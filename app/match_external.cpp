// `canhil match --external` (match_external.hpp).
#include "match_external.hpp"

#include <cstdio>

#include "canhil/emulator/external_driver.hpp"
#include "canhil/lockstep/conductor.hpp"
#include "team_processes.hpp"

namespace canhil::app {
namespace {

emulator::ExternalOptions driver_options(const emulator::Session& session, bool keep_trace) {
  emulator::ExternalOptions o;
  o.start_limit = from_seconds(attach_limit_s(session.scenario()));
  o.record_trace = keep_trace;  // a match keeps its figures, its frames only with --logs
  o.check_timing = true;
  return o;
}

// One half: the lockstep board, canhil's nodes on the robots' interfaces, and
// the teams' processes, started here and stopped when the half is over.
class ExternalHalf final : public emulator::HalfDriver {
 public:
  // `name`: "match 1, half 2" in messages; `file_prefix`: "match1-half2-" for the logs.
  ExternalHalf(emulator::Session& session, const ExternalMatch& how, const std::string& name,
               const std::string& file_prefix)
      : name_(name),
        conductor_(conductor_options(session.scenario())),
        driver_(session, conductor_, driver_options(session, how.logs.has_value())),
        processes_(conductor_.environment(how.shim, how.team_preload.empty() ? nullptr : how.team_preload.c_str()),
                   stderr, ProcessOutput{how.logs, file_prefix, true}),
        spin_(how.alone ? spin_the_bus(session) : nullptr) {
    std::fprintf(stderr, "canhil match: %s, the teams' processes:\n", name.c_str());
    const std::size_t expected = processes_.start_all(session);
    const double limit = attach_limit_s(session.scenario());
    const std::size_t attached = conductor_.wait_attached(expected, from_seconds(limit));
    if (attached < expected) {
      conductor_.release();  // the destructor does not run for a half that never began
      processes_.stop_all();
      char text[160];
      std::snprintf(text, sizeof text,
                    ": %zu of %zu process(es) attached within %g s (attach_limit_s in [external] or [teams.external])",
                    attached, expected, limit);
      throw emulator::ProcessStuck(name + text);
    }
  }
  ~ExternalHalf() override {
    conductor_.release();  // the half is over: their waits end, they take their SIGINT
    processes_.stop_all();
  }
  ExternalHalf(const ExternalHalf&) = delete;
  ExternalHalf& operator=(const ExternalHalf&) = delete;

  void run_until(Nanos end) override {
    try {
      driver_.run_until(end);
    } catch (const emulator::ProcessStuck& e) {
      char at[48];
      std::snprintf(at, sizeof at, " at t = %.3f s", to_seconds(driver_.now()));
      throw emulator::ProcessStuck(name_ + at + ": " + e.what());
    }
    processes_.reap(driver_.now());
    if (const std::string why = processes_.not_started(); !why.empty()) {
      char at[48];
      std::snprintf(at, sizeof at, " at t = %.3f s: ", to_seconds(driver_.now()));
      throw emulator::ProcessStuck(name_ + at + why);
    }
  }
  Nanos now() const override { return driver_.now(); }
  std::uint64_t ftt_violations(std::size_t robot) const override { return driver_.ftt_violations(robot); }
  std::uint64_t trace_hash() const override { return driver_.trace_hash(); }
  std::string trace() const override { return driver_.trace(); }

 private:
  std::string name_;
  lockstep::Conductor conductor_;
  emulator::ExternalDriver driver_;
  TeamProcesses processes_;
  std::unique_ptr<userbus::BrokerSpin> spin_;
};

}  // namespace

emulator::HalfDriverMaker external_halves(const ExternalMatch& how) {
  return [how](emulator::Session& session, std::uint64_t, int half) -> std::unique_ptr<emulator::HalfDriver> {
    const std::string match = std::to_string(how.match != nullptr ? *how.match : 1);
    const std::string h = std::to_string(half + 1);
    return std::make_unique<ExternalHalf>(session, how, "match " + match + ", half " + h,
                                          "match" + match + "-half" + h + "-");
  };
}

}  // namespace canhil::app
