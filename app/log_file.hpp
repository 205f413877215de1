// app/log_file.hpp — a candump log file, entry by entry, for the commands that
// judge one (`canhil timing`, `canhil timing --analyse`); and a run's logs
// written out (`canhil run`'s trace and world log, `canhil match --logs`).
#pragma once

#include <fstream>
#include <functional>
#include <string>

#include "args.hpp"
#include "canhil/base/located_error.hpp"
#include "canhil/frames/candump.hpp"

namespace canhil::app {

/// Hands every entry of the candump log `path` to `each`, in the file's order;
/// blank lines are skipped. A line that is not a log line is a LocatedError
/// naming the file and the line; an unreadable file a SetupError.
inline void for_each_log_entry(const std::string& path, const std::function<void(const frames::LogEntry&)>& each) {
  std::ifstream in(path);
  if (!in) throw SetupError("cannot read " + path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    frames::LogEntry e;
    std::string error;
    if (!frames::parse_log_line(line, e, &error)) throw LocatedError(path, n, "", error);
    each(e);
  }
}

/// Writes `text` (a trace, a world log) to `path`; a UsageError naming
/// `what` and the path when it cannot.
inline void write_file(const std::string& path, const std::string& text, const char* what) {
  std::ofstream out(path);
  out << text;
  if (!out) throw UsageError("cannot write the " + std::string(what) + " to " + path);
}

}  // namespace canhil::app
