// canhil/base/time.hpp — time as canhil counts it.
//
// Nanos is nanoseconds since a clock's epoch: the Unix epoch for the wall
// clock, the start of the run for a simulated one. Received frames carry
// their time in it. kNever and kLongAgo are the two ends nobody reaches;
// seconds and milliseconds as doubles are for reports and parameters only
// (they convert once, here, not in ad-hoc casts).
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <ratio>

namespace canhil {

using Nanos = std::chrono::nanoseconds;

/// "No wake-up wanted", "no deadline": later than any time a run reaches.
inline constexpr Nanos kNever = Nanos::max();
/// "Never happened" for last-seen times: far enough back that `now - kLongAgo`
/// exceeds any timeout, close enough that it cannot overflow (100 years).
inline constexpr Nanos kLongAgo = -std::chrono::duration_cast<Nanos>(std::chrono::hours(24 * 365 * 100));

/// Seconds as a double (reports, physics parameters).
constexpr double to_seconds(Nanos t) noexcept { return std::chrono::duration<double>(t).count(); }
/// Milliseconds as a double (reports).
constexpr double to_ms(Nanos t) noexcept { return std::chrono::duration<double, std::milli>(t).count(); }
namespace detail {
/// `count` units of Period as Nanos, rounded toward zero; beyond what Nanos
/// holds (about 292 years) kNever, or -kNever below; NaN 0.
template <class Period>
constexpr Nanos saturating_nanos(double count) noexcept {
  constexpr double kMostSeconds = 9.2e9;  // a little under Nanos::max(), 9.22e9 s
  constexpr double kMost = kMostSeconds * Period::den / Period::num;
  if (!(count == count)) return Nanos{0};
  if (count >= kMost) return kNever;
  if (count <= -kMost) return -kNever;
  return std::chrono::duration_cast<Nanos>(std::chrono::duration<double, Period>(count));
}
}  // namespace detail

/// A number of seconds as Nanos, rounded toward zero (as duration_cast does).
/// Beyond what Nanos holds it gives kNever (-kNever below) and NaN gives 0:
/// a conversion that would be undefined never happens.
constexpr Nanos from_seconds(double s) noexcept { return detail::saturating_nanos<std::ratio<1>>(s); }
/// A number of milliseconds as Nanos, rounded toward zero; saturating as from_seconds.
constexpr Nanos from_ms(double ms) noexcept { return detail::saturating_nanos<std::milli>(ms); }

/// The calling thread's CPU time so far (CLOCK_THREAD_CPUTIME_ID): for
/// benchmarks that must not count what other threads and processes did.
inline Nanos thread_cpu_now() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return Nanos(std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec);
}

/// The calling thread's CPU time that `work()` took.
template <class Work>
Nanos thread_cpu_of(Work&& work) {
  const Nanos start = thread_cpu_now();
  work();
  return thread_cpu_now() - start;
}

}  // namespace canhil
