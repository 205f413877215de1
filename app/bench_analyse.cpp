#include "bench_analyse.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <vector>

#include "canhil/timing/bus_analysis.hpp"

namespace canhil::app {
namespace {

using namespace std::chrono_literals;
using frames::FttKind;

constexpr int kMessages = 200;
constexpr int kRuns = 7;

// A robot-sized bus grown to 200 messages: harmonic periods of 10 ms to 1 s,
// sporadic gaps of 100 ms to 1 s, lengths of 1 to 8 bytes.
timing::BusSet big_set(bool ftt) {
  std::mt19937 rng(34);
  const Nanos periods[] = {10ms, 20ms, 50ms, 100ms, 200ms, 500ms, 1000ms};
  const Nanos gaps[] = {100ms, 200ms, 500ms, 1000ms};
  auto pick = [&](auto& list) { return list[std::uniform_int_distribution<std::size_t>(0, std::size(list) - 1)(rng)]; };
  auto dlc = [&] { return static_cast<std::uint8_t>(std::uniform_int_distribution<int>(1, 8)(rng)); };
  timing::BusSet set;
  set.ftt = ftt;
  if (ftt) set.messages.push_back({"TM", 0x010, false, 8, FttKind::kTrigger, -1, 10ms, {}, {}});
  const int periodic = ftt ? 31 : 100;
  for (int i = 0; i < periodic; ++i) {
    set.messages.push_back({"P" + std::to_string(i),
                            0x100u + static_cast<std::uint32_t>(i),
                            false,
                            dlc(),
                            FttKind::kSync,
                            ftt ? i : -1,
                            pick(periods),
                            {},
                            {}});
  }
  while (static_cast<int>(set.messages.size()) < kMessages) {
    const auto n = static_cast<std::uint32_t>(set.messages.size());
    set.messages.push_back(
        {"S" + std::to_string(n), 0x300u + n, false, dlc(), FttKind::kAsync, -1, {}, pick(gaps), {}});
  }
  return set;
}

// Median and longest of kRuns analyses, in ms.
std::pair<double, double> time_analysis(const timing::BusSet& set, bool* schedulable) {
  std::vector<double> ms;
  for (int r = 0; r < kRuns; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const timing::BusAnalysis a = timing::analyse_bus(set, timing::AnalysisConfig{});
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    *schedulable = a.schedulable();
  }
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms.back()};
}

}  // namespace

bool bench_analyse() {
  std::printf("canhil bench: timing --analyse of a %d-message set, what-if included (median of %d runs)\n", kMessages,
              kRuns);
  bool met = true;
  for (const bool ftt : {true, false}) {
    bool schedulable = false;
    const auto [median, longest] = time_analysis(big_set(ftt), &schedulable);
    const bool ok = median <= 50.0;
    met = met && ok;
    std::printf("  %-44s %8.2f ms (longest %.2f ms; %s)  target <= 50 ms: %s\n",
                ftt ? "FTT-CAN: TM, 31 synchronous, 168 sporadic:" : "native CAN: 100 periodic, 100 sporadic:", median,
                longest, schedulable ? "schedulable" : "not schedulable", ok ? "met" : "MISSED");
  }
  return met;
}

}  // namespace canhil::app
