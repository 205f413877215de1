// canhil/rtdb/replicator.hpp — the stand-in for the team's wireless: copies
// each agent's shared items into every other agent's database, through a
// Database (canhil's RTDB or the team's own library).
//
// Call cycle(now) every `period` (the emulator's laptop link does; run() does
// it on a clock of its own, as canhil rtdb replicate), and deliver(now) in
// between when copies are delayed. For
// each agent a and each of a's shared items: read it in a's database, then
// write it, as a's item, into every other agent's database. Each copy is lost
// with probability `loss` (seeded, so runs repeat) and otherwise arrives
// `delay` later, aged by its age when read plus its time in flight. An item
// never written is not copied. Not thread-safe; the clock is the caller's and
// never goes back.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <random>
#include <vector>

#include "canhil/rtdb/database.hpp"

namespace canhil::rtdb {

struct ReplicatorConfig {
  std::chrono::nanoseconds period = std::chrono::milliseconds(100);
  std::chrono::nanoseconds delay{0};
  double loss = 0.0;  ///< 0..1, per copy
  std::uint64_t seed = 1;
};

struct ReplicatorStats {
  std::uint64_t cycles = 0;
  std::uint64_t copied = 0;         ///< copies written
  std::uint64_t lost = 0;           ///< copies dropped (loss)
  std::uint64_t never_written = 0;  ///< shared items not copied: never written (libraries that can tell)
};

class Replicator {
 public:
  /// Copies through `db`, which must reach every agent (Scope::kAllAgents;
  /// SetupError otherwise) and outlive the replicator.
  Replicator(Database& db, const ReplicatorConfig& config);
  /// One replication cycle at time `now` (any monotonic time base), and
  /// delivery of every delayed copy that is due.
  void cycle(std::chrono::nanoseconds now);
  /// Delivery of every delayed copy due at `now`, copying nothing new.
  void deliver(std::chrono::nanoseconds now);
  /// Runs until `stop`: a cycle every period from now() on (a stall skips the
  /// cycles it missed rather than bursting), and each delayed copy delivered
  /// when it is due, not at the next cycle. `sleep_until(t)` returns at `t` or
  /// earlier (then the loop looks at `stop` and sleeps again). `canhil rtdb
  /// replicate` runs this on the wall clock.
  void run(const std::function<std::chrono::nanoseconds()>& now,
           const std::function<void(std::chrono::nanoseconds)>& sleep_until, const std::atomic<bool>& stop);
  /// Copies read but not delivered yet.
  std::size_t in_flight() const noexcept { return in_flight_.size(); }
  /// When the first copy in flight is due (nothing in flight: nullopt).
  std::optional<std::chrono::nanoseconds> next_due() const {
    if (in_flight_.empty()) return std::nullopt;
    return in_flight_.front().due;
  }
  const ReplicatorStats& stats() const noexcept { return stats_; }
  const ReplicatorConfig& config() const noexcept { return config_; }

 private:
  struct InFlight {
    std::chrono::nanoseconds due;
    int to_agent;
    int from_agent;
    int item;
    int age_ms;  // age when read
    std::chrono::nanoseconds read_at;
    std::vector<std::byte> value;
  };
  Database& db_;
  ReplicatorConfig config_;
  std::mt19937_64 rng_;
  std::deque<InFlight> in_flight_;  // in order of `due`: the delay is fixed
  std::vector<std::byte> value_;    // the item being copied
  ReplicatorStats stats_;
};

}  // namespace canhil::rtdb
