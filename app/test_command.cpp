// `canhil test FILES...`: a team's regression tests as files (verdict/),
// run in virtual time, a line per expectation, JUnit XML for the CI.
#include <cmath>
#include <cstdio>
#include <fstream>

#include "args.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/external/time_shim.hpp"
#include "canhil/verdict/junit.hpp"
#include "canhil/verdict/verdict.hpp"
#include "commands.hpp"
#include "stop_signals.hpp"

namespace canhil::app {

int run_test(Args& args, const std::optional<std::string>& dbc) {
  const auto junit = args.option("--junit");
  const auto artifacts = args.option("--artifacts");
  const double jobs = number_option(args, "--jobs", 1);
  if (jobs < 1 || jobs > 256 || std::floor(jobs) != jobs) throw UsageError("--jobs takes a whole number from 1 to 256");
  const bool quiet = args.flag("--quiet");
  const bool external = args.flag("--external");
  std::vector<std::string> words = args.positionals();
  words.erase(words.begin());  // "test"
  if (words.empty()) throw UsageError("test takes one or more test files (emulator/scenarios/tests/*.toml)");
  std::vector<std::filesystem::path> files(words.begin(), words.end());
  verdict::TestOptions options;
  options.dbc = dbc;
  if (artifacts) options.artifacts = *artifacts;
  if (external || verdict::any_with_processes(files)) {
    // canhil under the time shim before anything runs (it may start itself again).
    options.external = external;
    options.shim = external::find_timeshim();
    options.team_preload = external::preload_shim_into_self(options.shim);
    options.alone = jobs == 1;
  }
  // Runs of its own: RTDB keys of this process, so it never meets a live robot's database.
  external::use_private_rtdb_keys(external::kRunKeyPrefix);
  stop_on_signals();
  std::size_t passed = 0, failed = 0, errors = 0, expectations = 0;
  const auto results =
      verdict::run_test_files(files, static_cast<int>(jobs), options, g_stop, [&](const verdict::FileResult& r) {
        if (!quiet || !r.passed()) {
          std::fputs(verdict::format_result(r).c_str(), stdout);
          std::fflush(stdout);
        }
        errors += r.error.empty() ? 0U : 1U;
        expectations += r.verdicts.size();
        failed += r.failures();
        passed += r.verdicts.size() - r.failures();
      });
  std::printf("canhil test: %zu file(s), %zu expectation(s): %zu passed, %zu failed, %zu file(s) with errors%s\n",
              results.size(), expectations, passed, failed, errors, g_stop ? " (stopped)" : "");
  if (junit) {
    std::ofstream out(*junit);
    out << verdict::junit_xml(results);
    if (!out) throw SetupError("cannot write the JUnit report " + *junit);
    std::printf("JUnit report written to %s\n", junit->c_str());
  }
  if (g_stop) return 130;
  return failed == 0 && errors == 0 && results.size() == files.size() ? 0 : 1;
}

}  // namespace canhil::app
