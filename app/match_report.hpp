// app/match_report.hpp — `canhil match --report RECORDS.jsonl...`: records
// from any number of files (many machines, any order) merged into one
// report: wins, draws and losses, the goal difference with its 95 % interval,
// the win rate with its Wilson interval, whether the teams differ
// significantly, every other figure per team (emulator/match_stats.hpp).
// Records of another scenario, DBC or match length, and a seed twice, are
// refused by name.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace canhil::app {

/// Prints the report (or its JSON), writes the SVG when asked; 0, or throws
/// SetupError naming the file, line and what is wrong.
int run_match_report(const std::vector<std::string>& files, bool json, const std::optional<std::string>& svg);

}  // namespace canhil::app
