// app/match_records.hpp — one JSON line per match (`canhil match --records`):
// what a match was (scenario and DBC hashes, canhil's version, the match's
// length, the teams' process command lines when external) and what it gave
// (score, possession, shots, kicks, faults, FTT violations, solver messages,
// wall and virtual time, the hash of its trace), so that matches from many
// machines can be merged (`--report`) and any one played again and checked.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "canhil/emulator/match.hpp"
#include "canhil/emulator/match_stats.hpp"

namespace canhil::app {

/// What every record of one batch shares.
struct RecordContext {
  std::string scenario;       ///< its path as given
  std::string scenario_hash;  ///< FNV-1a of the file's bytes, hex
  std::string dbc_hash;
  std::string version;
  int halves = 2;
  double half_s = 600;
  std::vector<std::string> teams;                   ///< names, in the scenario's order
  std::vector<std::vector<std::string>> processes;  ///< per team, when external
};

/// FNV-1a (64 bits) of a file's bytes as 16 hex digits; SetupError naming it when unreadable.
std::string file_hash(const std::string& path);

nlohmann::json match_record(const emulator::MatchResult& r, const RecordContext& context);
/// A match whose process died (`why`: how), or was stopped for not answering.
nlohmann::json failed_record(std::uint64_t seed, const std::string& why, const RecordContext& context);
/// The figures of a record (MatchResult's fields; goals listed, solver counts).
emulator::MatchResult result_of(const nlohmann::json& record);
emulator::MatchSummary summary_of(const nlohmann::json& record);

/// "1..200", "7", "1,5,9", "1..10,20..30": the seeds in the order given;
/// UsageError-worthy text (std::invalid_argument) for anything else or more than 1e6.
std::vector<std::uint64_t> parse_seeds(const std::string& text);

}  // namespace canhil::app
