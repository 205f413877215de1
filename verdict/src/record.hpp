// verdict/src/record.hpp — what a test's run recorded for its expectations
// (run_test.cpp fills it, judge.cpp judges each expectation on it). Not
// installed.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/emulator/goal_watcher.hpp"
#include "canhil/external/team_processes.hpp"
#include "canhil/timing/analysis.hpp"
#include "canhil/timing/bound_check.hpp"
#include "canhil/verdict/test_file.hpp"
#include "canhil/verdict/verdict.hpp"

namespace canhil::verdict::detail {

/// Where a robot, or the ball, was at one sample (every elementary cycle).
struct Sample {
  double t = 0;
  double x = 0, y = 0;
};

/// An RTDB quantity at each sample: its value in SI units and its age.
struct RtdbSample {
  double t = 0;
  double value = 0;
  int age_ms = 0;
};

struct Record {
  double end_s = 0;
  std::vector<std::vector<Sample>> robots;  ///< per robot
  std::vector<Sample> ball;
  std::vector<bool> attacks_positive_x;  ///< per robot: its team's goal to score in
  std::vector<emulator::Goal> goals;
  std::vector<std::string> interfaces;                  ///< per robot
  std::vector<timing::TimingReport> bus;                ///< per robot, its whole trace
  std::vector<timing::BoundReport> bounds;              ///< per robot, with a within_bounds expectation
  bool schedulable = true;                              ///< the message set's analysis, with one
  std::string analysis;                                 ///< why not, when not
  std::vector<std::vector<Nanos>> latencies;            ///< per robot, the reference handler's
  std::map<std::size_t, std::vector<RtdbSample>> rtdb;  ///< per expectation index
  std::map<std::size_t, std::string> rtdb_errors;       ///< per expectation index: why it could not be read
  std::string where;                                    ///< where the trace and world log are (or how to keep them)
  // With the team's processes (--external):
  bool external = false;
  std::size_t started = 0;                 ///< processes waited for
  std::optional<std::string> stuck;        ///< why the run stopped early: one stopped answering, or never ran
  std::vector<external::ProcessEnd> ends;  ///< how those that ended, ended
};

/// The verdict of expectation `x` on `record`.
Verdict judge(const Expectation& x, const TestFile& test, const Record& record);

}  // namespace canhil::verdict::detail
