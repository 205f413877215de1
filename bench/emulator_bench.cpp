// emulator_bench — one robot's full node set with its physics, in virtual
// time, on the memory bus, with a laptop endpoint sending M6 in its slots.
// Prints simulated seconds per wall second. Target (issue 4): at least 300x.
#include <benchmark/benchmark.h>

#include <cmath>

#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/messages.hpp"
#include "support/one_robot_session.hpp"

namespace {

using namespace canhil;
using namespace std::chrono_literals;

// Sends M6 in its slots (like the laptop's handler) and counts what it hears.
class HandlerStandIn final : public can_nodes::Participant {
 public:
  HandlerStandIn(can_nodes::MemoryBus& bus, std::shared_ptr<const frames::MessageSet> set)
      : ep_(bus.attach("laptop", 1 << 16)), set_(std::move(set)) {}
  std::size_t poll() override {
    std::size_t n = 0;
    while (auto f = ep_->receive()) {
      ++n;
      frames::Tm tm;
      const std::uint32_t m6 = 1u << set_->ftt(set_->m6_1.message()).index;
      if (frames::is_message(f->frame, set_->tm.message()) && set_->tm.decode(f->frame, tm).ok()) {
        if (const auto start = sync_.on_tm(tm, f->time, 10ms, m6)) slot_ = *start;
      }
    }
    heard_ += n;
    return n;
  }
  void tick(Nanos now) override {
    slot_ = kNever;
    const double t = to_seconds(now);
    ep_->send(set_->m6_1.encode(frames::M6_1{0.3 * std::sin(t), 0.8 * std::cos(0.5 * t)}));
    ep_->send(set_->m6_2.encode(frames::M6_2{0.5, 0, 0}));
  }
  Nanos next_wakeup() const override { return slot_; }
  std::uint64_t heard_ = 0;

 private:
  std::unique_ptr<can_nodes::MemoryEndpoint> ep_;
  std::shared_ptr<const frames::MessageSet> set_;
  frames::SyncSlot sync_;
  Nanos slot_ = kNever;
};

void BM_OneRobotVirtualTime(benchmark::State& state) {
  physics::WorldParams wp;
  wp.robots = {physics::Placement{0, 0, 0}};
  wp.ball_start = {2, 2, wp.ball.radius_m};
  test::OneRobotSession session(frames::MessageSet::load(CANHIL_BENCH_DBC), wp);
  HandlerStandIn handler(session.bus(), session.messages());
  session.add(handler);
  std::int64_t simulated_s = 0;
  for (auto _ : state) {
    session.run_for(1s);
    ++simulated_s;
  }
  state.counters["realtime_factor"] = benchmark::Counter(static_cast<double>(simulated_s), benchmark::Counter::kIsRate);
  state.counters["frames_per_sim_s"] = static_cast<double>(handler.heard_) / static_cast<double>(simulated_s);
}
BENCHMARK(BM_OneRobotVirtualTime)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
