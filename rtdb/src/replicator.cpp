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

}  // namespace canhil::rtdb
