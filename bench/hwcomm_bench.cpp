// hwcomm_bench — the reference handler's own processing per bus->RTDB update
// (decode, RTDB write, bookkeeping), natively, with a real RTDB: the part of
// the receive-timestamp-to-RTDB latency (issue 5: p99 <= 200 us) that is the
// handler's; the rest is the kernel waking it (bench/handler_latency.sh
// measures the whole path on vcan).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "canhil/laptop/hwcomm.hpp"
#include "canhil/rtdb/rtdb.h"

namespace {

using namespace canhil;

void BM_HwCommUpdate(benchmark::State& state) {
  setenv("RTDB_KEY", std::to_string(0x5E000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  setenv("AGENT", "1", 1);
  if (DB_init() != 0) {
    state.SkipWithError("no RTDB");
    return;
  }
  auto set = frames::MessageSet::load(CANHIL_BENCH_DBC);
  Nanos now{0};
  // canhil's RTDB in canhil's layout (a team's library adds its own put cost).
  const auto db = rtdb::open_builtin(rtdb::Scope::kOneAgent);
  const rtdb::Layout layout = rtdb::Layout::shipped("canhil");
  laptop::HwComm hw(
      set, std::chrono::milliseconds(10), [](const frames::CanFrame&) { return true; }, [&] { return now; }, *db,
      layout, db->spaces().front());
  // One EC's worth of bus->RTDB traffic: M4_1 + M4_2 (CMD_POS), M8 (CMD_IMU), M9 (CMD_INFO, CMD_GRABBER_INFO), M2.
  const frames::CanFrame m4_1 = set->m4_1.encode({1.25, -0.5});
  const frames::CanFrame m4_2 = set->m4_2.encode({0.75, 3});
  const frames::CanFrame m8 = set->m8.encode({123.45, 7});
  const frames::CanFrame m9 = set->m9.encode({1, 0, 180.0, 50});
  const frames::CanFrame m2 = set->m2.encode({12.5, 12.4, 25.0, 180.0});
  std::int64_t updates = 0;
  for (auto _ : state) {
    hw.on_frame(m4_1, now);
    hw.on_frame(m4_2, now);
    hw.on_frame(m8, now);
    hw.on_frame(m9, now);
    hw.on_frame(m2, now);
    updates += 4;  // M4_1 only completes with M4_2
    now += std::chrono::microseconds(1);
  }
  state.counters["time_per_update"] =
      benchmark::Counter(static_cast<double>(updates), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  DB_free();
}
BENCHMARK(BM_HwCommUpdate);

}  // namespace

BENCHMARK_MAIN();
