// `canhil match --external`'s halves (external_half.hpp).
#include "canhil/external/external_half.hpp"

#include <cstdio>

#include "canhil/external/external_run.hpp"

namespace canhil::external {
namespace {

// One half: an ExternalRun started when the half is made, stopped when it ends.
class ExternalHalf final : public emulator::HalfDriver {
 public:
  ExternalHalf(emulator::Session& session, ExternalSetup setup) : run_(session, std::move(setup)) {
    std::fprintf(stderr, "canhil match: %s, the teams' processes:\n", run_.name().c_str());
    run_.start();
  }
  ExternalHalf(const ExternalHalf&) = delete;
  ExternalHalf& operator=(const ExternalHalf&) = delete;

  void run_until(Nanos end) override { run_.run_until(end); }
  Nanos now() const override { return run_.now(); }
  std::uint64_t ftt_violations(std::size_t robot) const override { return run_.driver().ftt_violations(robot); }
  std::uint64_t trace_hash() const override { return run_.driver().trace_hash(); }
  std::string trace() const override { return run_.driver().trace(); }

 private:
  ExternalRun run_;
};

}  // namespace

emulator::HalfDriverMaker external_halves(const ExternalMatch& how) {
  return [how](emulator::Session& session, std::uint64_t, int half) -> std::unique_ptr<emulator::HalfDriver> {
    const std::string match = std::to_string(how.match != nullptr ? *how.match : 1);
    const std::string h = std::to_string(half + 1);
    ExternalSetup setup;
    setup.shim = how.shim;
    setup.team_preload = how.team_preload;
    setup.say = stderr;  // a match's stdout is the table, or JSON
    setup.output = ProcessOutput{how.logs, "match" + match + "-half" + h + "-", true};
    setup.spin_bus = how.alone;
    setup.record_trace = how.logs.has_value();  // a match keeps its figures, its frames only with --logs
    setup.check_timing = true;
    setup.name = "match " + match + ", half " + h;
    return std::make_unique<ExternalHalf>(session, std::move(setup));
  };
}

}  // namespace canhil::external
