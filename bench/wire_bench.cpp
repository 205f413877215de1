// wire_bench — the bus model alone (wire/wire_bus.hpp): the CPU time of one
// frame through a busy bus of five controllers, each keeping a frame queued
// (submit, arbitration, its bits, its end). What a timed run pays for each
// frame besides the runner's instant; `canhil bench --part wire` measures
// the run itself.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>
#include <vector>

#include "canhil/wire/wire_bus.hpp"

namespace {

using namespace canhil;

void BM_WireBusBusyFiveControllers(benchmark::State& state) {
  wire::WireBus bus({});
  constexpr std::uint32_t kControllers = 5;
  for (std::uint32_t c = 0; c < kControllers; ++c) bus.add_controller("c" + std::to_string(c));
  std::vector<wire::WireEvent> events;
  frames::WireFrame f;
  f.len = 8;
  std::uint64_t given = 0, delivered = 0;
  Nanos now{0};
  for (auto _ : state) {
    const auto c = static_cast<wire::ControllerId>(given % kControllers);
    f.id = 0x100u + c;
    f.data[0] = static_cast<std::uint8_t>(given++);
    bus.submit(c, f, now);
    now = std::max(now, bus.next_event());
    events.clear();
    bus.advance(now, events);
    delivered += events.size();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(delivered));
  state.counters["time_per_frame"] =
      benchmark::Counter(static_cast<double>(delivered), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_WireBusBusyFiveControllers);

}  // namespace

BENCHMARK_MAIN();
