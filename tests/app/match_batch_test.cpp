// `canhil match` batches: --seeds in parallel workers give the records of a
// sequential run; a match whose process dies is recorded as failed and the
// batch goes on; --report merges records from any files, with statistics
// worked out by hand, and refuses duplicates and records of another scenario.
// Silent trouble (test::WatchedTest): canhil runs in a process of its own
// here, so its nodes' counters are not this test's to watch; the same runs
// in process are watched (tests/emulator/match_test.cpp).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "support/test_paths.hpp"

namespace {

using canhil::test::canhil;
using canhil::test::CliRun;
using canhil::test::has;
namespace fs = std::filesystem;

std::string scratch(const std::string& name) {
  std::string path = canhil::test::build_dir() + "/match_batch_" + name;
  fs::remove(path);
  return path;
}

std::vector<nlohmann::json> records_of(const std::string& path) {
  std::vector<nlohmann::json> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) out.push_back(nlohmann::json::parse(line));
  return out;
}

// A batch's bookkeeping on instant buses: cheap under the sanitizers (the
// timed match's play is MatchTest's).
constexpr const char* kShort =
    "match emulator/scenarios/two_teams.toml --halves 1 --half-minutes 0.02 --quiet --bit-rate 0";

TEST(MatchBatch, TwoWorkersGiveTheRecordsOfOneTraceHashesIncluded) {
  const std::string one = scratch("one.jsonl");
  const std::string two = scratch("two.jsonl");
  const CliRun a = canhil(std::string(kShort) + " --seeds 1..4 --jobs 1 --records " + one);
  const CliRun b = canhil(std::string(kShort) + " --seeds 1..4 --jobs 2 --records " + two);
  ASSERT_EQ(a.status, 0) << a.out;
  ASSERT_EQ(b.status, 0) << b.out;
  std::vector<nlohmann::json> ra = records_of(one), rb = records_of(two);
  ASSERT_EQ(ra.size(), 4u);
  for (auto* rs : {&ra, &rb}) {
    for (auto& r : *rs) r.erase("wall_s");
  }
  EXPECT_EQ(ra, rb);
  for (std::size_t k = 0; k < ra.size(); ++k) EXPECT_EQ(ra[k]["seed"], k + 1) << "in the order of the seeds";
  EXPECT_NE(ra[0]["trace_hash"], ra[1]["trace_hash"]);
  EXPECT_TRUE(has(b, "2 at a time")) << b.out;
  // The same output line by line, but for the wall times, the workers and the records' file.
  auto table = [](const std::string& out) {
    std::string text = std::regex_replace(out, std::regex(" in [0-9.]+ s( of wall time)? \\([^)]*\\)"), "");
    text = std::regex_replace(text, std::regex(", 2 at a time"), "");
    return std::regex_replace(text, std::regex("records: .*\\n"), "");
  };
  EXPECT_EQ(table(a.out), table(b.out));
}

TEST(MatchBatch, JsonGivesTheRefereesCallsAndLogsKeepEveryHalfsTraceAndWorldLog) {
  const std::string dir = scratch("logs");
  fs::remove_all(dir);
  const CliRun run = canhil(
      "match emulator/scenarios/two_teams.toml --halves 2 --half-minutes 0.4 --seed 3 --jobs 1 --bit-rate 0 --json "
      "--logs " +
      dir);
  ASSERT_EQ(run.status, 0) << run.out;
  const nlohmann::json match = nlohmann::json::parse(run.out).at("matches").at(0);
  const nlohmann::json& calls = match.at("referee");
  EXPECT_EQ(calls.size(), match.at("referee_calls").get<std::size_t>()) << "the calls themselves, not their count";
  ASSERT_GT(calls.size(), 0u) << "24 s of play give the referee something to call";
  for (int half = 1; half <= 2; ++half) {
    const std::string name = dir + "/seed3-half" + std::to_string(half);
    std::ifstream trace(name + ".log");
    std::string first;
    ASSERT_TRUE(std::getline(trace, first)) << name << ".log";
    EXPECT_TRUE(std::regex_search(first, std::regex(R"(^\([0-9]+\.[0-9]{6}\) vcan[0-9]+ [0-9A-F]{3}#)"))) << first;
    // The world log's call lines are the calls the JSON gives for that half.
    std::ifstream world(name + ".csv");
    std::size_t in_log = 0;
    for (std::string line; std::getline(world, line);) in_log += line.rfind("#referee,", 0) == 0 ? 1U : 0U;
    std::size_t in_json = 0;
    for (const nlohmann::json& c : calls) {
      in_json += c.at("half") == half ? 1U : 0U;
      EXPECT_FALSE(c.at("restart").get<std::string>().empty()) << c;
    }
    EXPECT_EQ(in_log, in_json) << "half " << half;
  }
  fs::remove_all(dir);
}

TEST(MatchBatch, AMatchWhoseProcessDiesIsRecordedAsFailedAndTheBatchGoesOn) {
  const std::string path = scratch("killed.jsonl");
  const CliRun r = canhil(std::string(kShort) + " --seeds 1..4 --jobs 2 --records " + path, "CANHIL_MATCH_KILL_SEED=2");
  EXPECT_EQ(r.status, 1) << "a failed match fails the batch's exit status\n" << r.out;
  EXPECT_TRUE(has(r, "match 2 (seed 2): FAILED: its process was killed by signal 9")) << r.out;
  EXPECT_TRUE(has(r, "match 4 (seed 4): new ")) << "the batch went on\n" << r.out;
  const std::vector<nlohmann::json> rs = records_of(path);
  ASSERT_EQ(rs.size(), 4u);
  EXPECT_TRUE(rs[1]["failed"].get<std::string>().find("signal 9") != std::string::npos);
  EXPECT_TRUE(rs[2]["failed"].is_null());
}

// A record as canhil writes it, with the figures a test wants.
nlohmann::json record(std::uint64_t seed, int a, int b, const std::string& scenario_hash = "00000000000000aa") {
  auto team = [](const char* name, int goals) {
    return nlohmann::json{{"team", name},   {"goals", goals}, {"possession_s", 10.0}, {"possession_pct", 50.0},
                          {"shots", goals}, {"kicks", 2},     {"faults", 0},          {"ftt_violations", 0}};
  };
  return {{"seed", seed},
          {"scenario", "s.toml"},
          {"scenario_hash", scenario_hash},
          {"dbc_hash", "00000000000000bb"},
          {"canhil", "0.1.0"},
          {"halves", 2},
          {"half_s", 120.0},
          {"teams", {team("new", a), team("old", b)}},
          {"goals", nlohmann::json::array()},
          {"referee_calls", 0},
          {"solver", {{"messages", 0}, {"internal_errors", 0}, {"errors", 0}, {"first", nlohmann::json::array()}}},
          {"virtual_s", 240.0},
          {"wall_s", 3.0},
          {"trace_hash", "0123456789abcdef"},
          {"stopped", false},
          {"failed", nullptr}};
}

void write(const std::string& path, const std::vector<nlohmann::json>& rs) {
  std::ofstream out(path);
  for (const auto& r : rs) out << r.dump() << "\n";
}

TEST(MatchBatch, TheReportOfTenMatchesSixWonTwoDrawnTwoLost) {
  // Spread over two files, out of order.
  const std::string a = scratch("a.jsonl");
  const std::string b = scratch("b.jsonl");
  write(a, {record(7, 1, 0), record(2, 2, 0), record(9, 0, 1), record(4, 1, 1), record(1, 3, 1)});
  write(b, {record(3, 1, 0), record(10, 0, 2), record(5, 2, 1), record(6, 0, 0), record(8, 1, 0)});
  const CliRun r = canhil("match --report " + a + " " + b);
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(has(r, "10 match(es) of s.toml (2 x 2 min) from 2 file(s)")) << r.out;
  EXPECT_TRUE(has(r, "new against old: 6 won, 2 drawn, 2 lost")) << r.out;
  // Differences 1 2 -1 0 2 1 -2 1 0 1: mean 0.5, sd 1.2693, t(0.975, 9) 2.2622: +-0.9080.
  EXPECT_TRUE(has(r, "+0.50 per match, 95 % interval -0.41 .. +1.41")) << r.out;
  // Wilson for 6 in 10: 31 % .. 83 % (tests/emulator/match_stats_test.cpp works it out).
  EXPECT_TRUE(has(r, "win rate of new: 60 % (Wilson 95 %: 31 % .. 83 %)")) << r.out;
  EXPECT_TRUE(has(r, "do not differ significantly at 5 % (sign test on the 8 decided matches: p = 0.289)")) << r.out;
  const CliRun j1 = canhil("match --report --json " + a + " " + b);
  const CliRun j2 = canhil("match --report --json " + b + " " + a);
  EXPECT_EQ(j1.out, j2.out) << "the order of the files does not matter";
  EXPECT_EQ(nlohmann::json::parse(j1.out)["wins"], 6);
}

TEST(MatchBatch, TheReportRefusesASeedTwiceAndAnotherScenarioByName) {
  const std::string a = scratch("dup_a.jsonl");
  const std::string b = scratch("dup_b.jsonl");
  write(a, {record(1, 1, 0), record(2, 0, 0)});
  write(b, {record(3, 1, 0), record(2, 0, 1)});
  CliRun r = canhil("match --report " + a + " " + b);
  EXPECT_NE(r.status, 0);
  EXPECT_TRUE(has(r, b + ":2: seed 2 again (first at " + a + ":2)")) << r.out;
  write(b, {record(3, 1, 0, "00000000000000cc")});
  r = canhil("match --report " + a + " " + b);
  EXPECT_NE(r.status, 0);
  EXPECT_TRUE(has(r, b + ":1: scenario_hash \"00000000000000cc\" is not \"00000000000000aa\" of " + a + ":1")) << r.out;
  std::ofstream(b) << "{\"seed\": 4}\n";
  r = canhil("match --report " + a + " " + b);
  EXPECT_TRUE(has(r, b + ":1: not a match record")) << r.out;
}

TEST(MatchBatch, TheBenchmarkPrintsBothRatesAndTheirRatio) {
  // Wall-clock: printed, never judged here (the exit status says met or missed).
  const CliRun r = canhil("bench --part jobs --seconds 0.1");
  EXPECT_TRUE(r.status == 0 || r.status == 1) << r.out;
  EXPECT_TRUE(has(r, "--jobs 1: 8 halves in")) << r.out;
  EXPECT_TRUE(has(r, "--jobs 2: 8 halves in")) << r.out;
  EXPECT_TRUE(has(r, "throughput, --jobs 2 / --jobs 1: ")) << r.out;
}

}  // namespace
