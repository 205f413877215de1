// canhil/verdict/verdict.hpp — a test file run in virtual time and judged:
// one verdict per expectation with what was measured, when, and where to
// look; the same seed gives the same verdicts on every machine. `canhil test`
// runs files with it, in worker processes with --jobs.
#pragma once

#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "canhil/verdict/test_file.hpp"

namespace canhil::verdict {

struct Verdict {
  std::string name;   ///< the expectation's
  std::string check;  ///< its key (check_key)
  int line = 0;       ///< in the test file
  bool passed = false;
  std::string measured;  ///< what was measured, with its unit ("0.18 m at 2.41 s")
  std::string message;   ///< on failure: what went wrong, when, and where to look
};

struct FileResult {
  std::string file;  ///< as given
  std::string name;  ///< the test's
  /// Set when the file or its scenario could not be run at all (a mistake in
  /// it, a library missing): every expectation then counts as an error.
  std::string error;
  std::vector<Verdict> verdicts;
  double virtual_s = 0;   ///< how far the run got
  double wall_s = 0;      ///< how long it took
  std::string artifacts;  ///< the folder its trace and world log went to (with one asked)
  bool passed() const noexcept;
  std::size_t failures() const noexcept;
};

struct TestOptions {
  std::optional<std::string> dbc;  ///< the message set (default: canhil's shipped DBC)
  /// Where each file's trace, world log and verdicts go: a folder per file,
  /// named after it (empty: nothing kept).
  std::filesystem::path artifacts;
  /// The file's folder under `artifacts` (empty: the file's name without
  /// .toml; run_test_files gives files of one name folders apart).
  std::string artifact_name;
  /// With the team's own processes, the scenario's [external] command
  /// lines, in lockstep (docs/lockstep.md), for every file (a file that says
  /// `external = true` runs so anyway): this process is under the time
  /// shim already (external::preload_shim_into_self) and the robots'
  /// interfaces exist (canhil's user-space bus, or vcan). Their output and
  /// canhil's word on them go with the artifacts (else to stderr).
  bool external = false;
  std::string shim;          ///< the time shim (external::find_timeshim)
  std::string team_preload;  ///< what the team's processes keep preloaded after it
  bool alone = true;         ///< no other run beside it (--jobs 1): the bus's broker may spin
};

/// Runs one test file; never throws for what is wrong with the file or its
/// scenario (FileResult::error says it, naming the file, line and field).
FileResult run_test_file(const std::filesystem::path& path, const TestOptions& options);
/// Runs an already read test.
FileResult run_test(const TestFile& test, const TestOptions& options);

/// Every file, `jobs` at a time in worker processes (1: in this one), the
/// results in the order of the files whatever order they finish in; `each`
/// is called with each result in that order. Stops handing out files once
/// `stop` is set.
std::vector<FileResult> run_test_files(const std::vector<std::filesystem::path>& files, int jobs,
                                       const TestOptions& options, const std::atomic<bool>& stop,
                                       const std::function<void(const FileResult&)>& each = {});

/// Whether any of `files` runs with the team's processes (`external =
/// true`); a file that cannot be read counts as not.
bool any_with_processes(const std::vector<std::filesystem::path>& files);

/// A result as one line of JSON (what a worker sends back) and back.
std::string to_json_line(const FileResult& r);
FileResult from_json_line(const std::string& line);

/// The lines `canhil test` prints for a file: a header, one line per
/// expectation (PASS/FAIL, name, measured), and each failure's message.
std::string format_result(const FileResult& r);

}  // namespace canhil::verdict
