#include "bench_realtime.hpp"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <span>
#include <thread>
#include <utility>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/fifo_scheduling.hpp"
#include "canhil/frames/ftt.hpp"
#include "run_realtime.hpp"

namespace canhil::app {
namespace {

using namespace std::chrono_literals;

constexpr std::uint32_t kBareLoopId = 0x7FE;
constexpr std::uint32_t kRateId = 0x7FD;
constexpr std::size_t kWarmup = 50;  // releases left out at the start (caches, page faults, the first ECs)

/// A socket on its own thread keeping every frame its filters pass, with kernel timestamps.
class Listener {
 public:
  Listener(const std::string& iface, std::span<const can_nodes::Filter> filters) {
    can_nodes::SocketCanOptions options;
    options.receive_buffer_bytes = 16 << 20;
    options.filters.assign(filters.begin(), filters.end());
    bus_ = can_nodes::SocketCanBus::open(iface, options);
    thread_ = std::thread([this] { loop(); });
  }
  ~Listener() { stop(); }
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;

  std::uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  /// Stops listening (after reading what is queued) and hands over the frames.
  std::vector<frames::TimedFrame> stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
    return std::move(frames_);
  }
  can_nodes::BusStats stats() const { return bus_->stats(); }

 private:
  void loop() {
    while (true) {
      const bool last = done_.load();
      if (bus_->wait_readable(10ms) || last) {
        while (auto f = bus_->receive()) {
          frames_.push_back(*f);
          count_.fetch_add(1, std::memory_order_relaxed);
        }
      }
      if (last) return;
    }
  }

  std::unique_ptr<can_nodes::SocketCanBus> bus_;
  std::vector<frames::TimedFrame> frames_;
  std::atomic<std::uint64_t> count_{0};
  std::atomic<bool> done_{false};
  std::thread thread_;
};

std::uint32_t sequence_of(const frames::CanFrame& f) {
  std::uint32_t k = 0;
  std::memcpy(&k, f.data.data(), sizeof k);
  return k;
}

double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0;
  const auto at = static_cast<std::size_t>(std::lround(p * static_cast<double>(sorted.size() - 1)));
  return sorted[std::min(at, sorted.size() - 1)];
}

// Releases (period index, kernel time) -> jitter against the best-aligned schedule.
JitterFigures jitter_of(std::vector<std::pair<std::int64_t, Nanos>> releases, Nanos period) {
  JitterFigures j;
  if (releases.size() <= kWarmup + 1) return j;
  releases.erase(releases.begin(), releases.begin() + kWarmup);
  Nanos phase = kNever;
  for (const auto& [k, t] : releases) phase = std::min(phase, t - period * k);
  std::vector<double> late;
  late.reserve(releases.size());
  for (const auto& [k, t] : releases) {
    late.push_back(std::chrono::duration<double, std::micro>(t - period * k - phase).count());
  }
  std::sort(late.begin(), late.end());
  j.releases = releases.size();
  const std::int64_t span = releases.back().first - releases.front().first + 1;
  j.missing = static_cast<std::uint64_t>(std::max<std::int64_t>(0, span - static_cast<std::int64_t>(releases.size())));
  j.p50_us = percentile(late, 0.50);
  j.p99_us = percentile(late, 0.99);
  j.max_us = late.back();
  return j;
}

timespec to_timespec(Nanos t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(t.count() % 1'000'000'000);
  return ts;
}

// Runs `send`, then waits until the listener has everything or nothing more comes.
RateFigures measure_rate(const std::string& iface, std::uint64_t frames, const std::function<std::uint64_t()>& send,
                         bool check_sequence) {
  const can_nodes::Filter only[] = {can_nodes::Filter::exact(kRateId)};
  Listener listener(iface, only);
  RateFigures r;
  r.sent = send();
  std::uint64_t seen = listener.count();
  for (int quiet = 0; quiet < 20 && listener.count() < r.sent; ++quiet) {
    std::this_thread::sleep_for(50ms);
    if (listener.count() != seen) quiet = 0;
    seen = listener.count();
  }
  const std::vector<frames::TimedFrame> got = listener.stop();
  r.received = got.size();
  std::uint64_t gaps = 0;
  if (check_sequence) {
    for (std::size_t i = 1; i < got.size(); ++i) gaps += sequence_of(got[i].frame) != sequence_of(got[i - 1].frame) + 1;
  }
  r.lost = (frames > r.received ? frames - r.received : 0) + listener.stats().rx_overflow + gaps;
  if (got.size() > 1) {
    r.frames_per_s = static_cast<double>(got.size() - 1) / to_seconds(got.back().time - got.front().time);
  }
  return r;
}

}  // namespace

JitterFigures bare_loop_jitter(const std::string& iface, double seconds, Nanos period, int priority) {
  const can_nodes::Filter only[] = {can_nodes::Filter::exact(kBareLoopId)};
  Listener listener(iface, only);
  auto tx = can_nodes::SocketCanBus::open(iface);
  const emulator::MemoryLock memory(priority > 0);
  const emulator::FifoScheduling fifo(priority);
  const auto n = static_cast<std::uint32_t>(seconds / to_seconds(period));
  Nanos deadline = (can_nodes::WallClock{}.now() / period + 2) * period;
  for (std::uint32_t k = 0; k < n; ++k, deadline += period) {
    const timespec at = to_timespec(deadline);
    while (clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &at, nullptr) != 0) {
    }
    frames::CanFrame f = frames::make_data_frame(kBareLoopId, {0, 0, 0, 0});
    std::memcpy(f.data.data(), &k, sizeof k);
    tx->send(f);
  }
  std::this_thread::sleep_for(50ms);
  std::vector<std::pair<std::int64_t, Nanos>> releases;
  for (const auto& f : listener.stop()) releases.emplace_back(sequence_of(f.frame), f.time);
  return jitter_of(std::move(releases), period);
}

JitterFigures emulator_jitter(const std::string& iface, double seconds, const emulator::Scenario& scenario,
                              const emulator::SessionOptions& session, const emulator::RealtimeOptions& options) {
  const frames::MessageSet& set = *session.messages;
  const can_nodes::Filter only[] = {can_nodes::Filter::exact(set.tm.message().id())};
  emulator::RunOverrides alone_on_iface;
  alone_on_iface.robots = 1;
  alone_on_iface.interfaces = {iface};
  Listener listener(iface, only);
  {
    emulator::Session run(emulator::plan_run(scenario, session, alone_on_iface));
    struct Null {
      FILE* file = std::fopen("/dev/null", "w");
      ~Null() {
        if (file != nullptr) std::fclose(file);
      }
    } null;
    RealtimeOutput output;
    output.length = {seconds, "the bench"};
    output.out = null.file != nullptr ? null.file : stdout;
    run_realtime(run, options, output);
  }
  std::vector<std::pair<std::int64_t, Nanos>> releases;
  std::int64_t k = 0;
  std::uint16_t previous = 0;
  for (const auto& f : listener.stop()) {
    frames::Tm tm;
    if (!set.tm.decode(f.frame, tm).ok()) continue;
    if (!releases.empty()) k += static_cast<std::uint16_t>(tm.ec_counter - previous);  // 16-bit counter, unwrapped
    previous = tm.ec_counter;
    releases.emplace_back(k, f.time);
  }
  return jitter_of(std::move(releases), frames::FttConfig{}.elementary_cycle);
}

RateFigures canhil_rate(const std::string& iface, std::uint64_t frames) {
  double pace = 0;  // frames per second; 0: as fast as it goes
  RateFigures r;
  for (int attempt = 0; attempt < 6; ++attempt) {
    r = measure_rate(
        iface, frames,
        [&] {
          auto tx = can_nodes::SocketCanBus::open(iface);
          const Nanos start = can_nodes::WallClock{}.now();
          for (std::uint64_t i = 0; i < frames; ++i) {
            if (pace > 0 && i % 64 == 0) {
              const timespec at = to_timespec(start + std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(
                                                          static_cast<double>(i) / pace)));
              clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &at, nullptr);
            }
            frames::CanFrame f = frames::make_data_frame(kRateId, {0, 0, 0, 0, 0, 0, 0, 0});
            const auto seq = static_cast<std::uint32_t>(i);
            std::memcpy(f.data.data(), &seq, sizeof seq);
            tx->send(f);
          }
          return tx->stats().sent;
        },
        true);
    if (r.lost == 0) return r;
    pace = 0.8 * (pace > 0 ? std::min(pace, r.frames_per_s) : r.frames_per_s);
  }
  return r;
}

RateFigures cangen_rate(const std::string& iface, std::uint64_t frames) {
  if (std::system("command -v cangen > /dev/null 2>&1") != 0) {
    throw SetupError("cangen (can-utils) is not installed: apt-get install can-utils");
  }
  char id[8];
  std::snprintf(id, sizeof id, "%X", kRateId);
  const std::string command =
      "cangen " + iface + " -g 0 -p 10 -n " + std::to_string(frames) + " -I " + id + " -L 8 -D i > /dev/null 2>&1";
  return measure_rate(
      iface, frames,
      [&]() -> std::uint64_t {
        if (std::system(command.c_str()) != 0) throw SetupError("`" + command + "` failed");
        return frames;
      },
      false);
}

}  // namespace canhil::app
