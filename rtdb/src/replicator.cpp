#include "canhil/rtdb/replicator.hpp"

#include <algorithm>
#include <climits>

#include "canhil/base/setup_error.hpp"

namespace canhil::rtdb {

Replicator::Replicator(Database& db, const ReplicatorConfig& config) : db_(db), config_(config), rng_(config.seed) {
  if (db.scope() != Scope::kAllAgents) {
    throw SetupError("the replicator copies between every agent's database: open " + db.library() +
                     " for every agent (Scope::kAllAgents)");
  }
  if (config.period <= std::chrono::nanoseconds{0}) {
    throw SetupError("the replicator's period must be above 0 (a cycle every period)");
  }
  if (config.delay < std::chrono::nanoseconds{0}) throw SetupError("the replicator's delay cannot be negative");
  if (!(config.loss >= 0.0 && config.loss <= 1.0)) {
    throw SetupError("the replicator's loss is a probability: 0 to 1");
  }
}

void Replicator::cycle(std::chrono::nanoseconds now) {
  ++stats_.cycles;
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  const ItemTable& items = db_.items();
  const bool at_once = config_.delay <= std::chrono::nanoseconds{0};
  for (const int from : db_.spaces()) {
    for (const int item : items.items_of(from, ItemKind::kShared)) {
      value_.resize(*items.size(item));
      const std::optional<int> age = db_.get(from, from, item, value_);
      if (!age) continue;
      if (*age == Database::kNeverWritten) {
        ++stats_.never_written;
        continue;
      }
      for (const int to : db_.spaces()) {
        if (to == from) continue;
        if (config_.loss > 0 && chance(rng_) < config_.loss) {
          ++stats_.lost;
          continue;
        }
        if (at_once) {
          db_.put(to, from, item, value_, *age);
          ++stats_.copied;
        } else {
          in_flight_.push_back(InFlight{now + config_.delay, to, from, item, *age, now, value_});
        }
      }
    }
  }
  deliver(now);
}

void Replicator::deliver(std::chrono::nanoseconds now) {
  // Aged by the time in flight.
  while (!in_flight_.empty() && in_flight_.front().due <= now) {
    InFlight& f = in_flight_.front();
    const auto flight_ms = std::chrono::duration_cast<std::chrono::milliseconds>(now - f.read_at).count();
    const long long life = std::min<long long>(INT_MAX, f.age_ms + flight_ms);
    db_.put(f.to_agent, f.from_agent, f.item, f.value, static_cast<int>(life));
    ++stats_.copied;
    in_flight_.pop_front();
  }
}

void Replicator::run(const std::function<std::chrono::nanoseconds()>& now,
                     const std::function<void(std::chrono::nanoseconds)>& sleep_until, const std::atomic<bool>& stop) {
  std::chrono::nanoseconds next_cycle = now();
  while (!stop.load(std::memory_order_relaxed)) {
    const std::chrono::nanoseconds t = now();
    if (t >= next_cycle) {
      cycle(t);
      while (next_cycle <= t) next_cycle += config_.period;
    } else {
      deliver(t);
    }
    const auto due = next_due();
    sleep_until(due && *due < next_cycle ? *due : next_cycle);
  }
}

}  // namespace canhil::rtdb
