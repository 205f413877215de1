#include "canhil/can_nodes/clock.hpp"

#include <time.h>

#include "canhil/frames/demand.hpp"

namespace canhil::can_nodes {

Nanos WallClock::now() const noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::chrono::seconds(ts.tv_sec) + Nanos(ts.tv_nsec);
}

void SimulatedClock::advance(Nanos dt) {
  CANHIL_DEMAND(dt.count() >= 0, "simulated time cannot run backwards");
  now_ += dt;
}

void SimulatedClock::set(Nanos t) {
  CANHIL_DEMAND(t >= now_, "simulated time cannot run backwards");
  now_ = t;
}

}  // namespace canhil::can_nodes
