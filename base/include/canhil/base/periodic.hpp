// canhil/base/periodic.hpp — a period re-armed in one place: the instants
// first, first + period, first + 2 x period, ... of something done every
// period (the world's step in virtual and in real time, a motor node's tick).
// Whoever keeps one asks whether it is due and says how it moves on: by one
// period (a loop that is never late: virtual time), past now (a tick that may
// be taken late), or by whole periods given up (a real-time loop too far
// behind drops steps rather than running them in a burst).
#pragma once

#include <cstdint>

#include "canhil/base/time.hpp"

namespace canhil {

class Periodic {
 public:
  Periodic() = default;
  /// `period` above 0; `first`: the first instant due.
  Periodic(Nanos period, Nanos first) noexcept : period_(period), next_(first) {}

  Nanos period() const noexcept { return period_; }
  /// The next instant due.
  Nanos next() const noexcept { return next_; }
  bool due(Nanos now) const noexcept { return now >= next_; }
  /// The instant due taken: the next is one period on.
  void advance() noexcept { next_ += period_; }
  /// Every instant up to `now` taken at once: the next is the first after
  /// `now`, whole periods on from the last.
  void advance_past(Nanos now) noexcept {
    if (now < next_) return;
    next_ += period_ * ((now - next_) / period_ + 1);
  }
  /// `n` instants given up: the next is `n` periods further on.
  void skip(std::int64_t n) noexcept { next_ += period_ * n; }

 private:
  Nanos period_{1};
  Nanos next_ = kNever;
};

}  // namespace canhil
