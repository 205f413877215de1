#include "canhil/can_nodes/clock.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>

#include "canhil/base/demand.hpp"

namespace canhil::can_nodes {

void WallClock::sleep_until(Nanos t, Nanos at_most) noexcept {
  const Nanos until = std::min(t, WallClock{}.now() + at_most);
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(until.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(until.count() % 1'000'000'000);
  while (clock_nanosleep(CLOCK_REALTIME, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

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
