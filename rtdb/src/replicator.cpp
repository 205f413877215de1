#include "canhil/rtdb/replicator.hpp"

#include <algorithm>
#include <climits>

#include "canhil/rtdb/rtdb.h"

namespace canhil::rtdb {

Replicator::Replicator(const ReplicatorConfig& config) : config_(config), rng_(config.seed) {}

void Replicator::cycle(std::chrono::nanoseconds now) {
  ++stats_.cycles;
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  const int agents = DB_agent_count();
  const int items = DB_item_count();
  for (int from = 0; from < agents; ++from) {
    for (int item = 0; item < items; ++item) {
      if (DB_item_shared(from, item) != 1) continue;
      std::vector<unsigned char> value(static_cast<std::size_t>(DB_item_size(item)));
      const int age = DB_get_from(from, from, item, value.data());
      if (age < 0) continue;
      for (int to = 0; to < agents; ++to) {
        if (to == from) continue;
        if (config_.loss > 0 && chance(rng_) < config_.loss) {
          ++stats_.lost;
          continue;
        }
        in_flight_.push_back(InFlight{now + config_.delay, to, from, item, age, now, value});
      }
    }
  }
  // Deliver what is due, aged by its time in flight.
  std::stable_sort(in_flight_.begin(), in_flight_.end(),
                   [](const InFlight& a, const InFlight& b) { return a.due < b.due; });
  while (!in_flight_.empty() && in_flight_.front().due <= now) {
    InFlight& f = in_flight_.front();
    const auto flight_ms = std::chrono::duration_cast<std::chrono::milliseconds>(now - f.read_at).count();
    const long long life = std::min<long long>(INT_MAX, f.age_ms + flight_ms);
    if (DB_put_in(f.to_agent, f.from_agent, f.item, f.value.data(), static_cast<int>(life)) >= 0) ++stats_.copied;
    in_flight_.pop_front();
  }
}

}  // namespace canhil::rtdb
