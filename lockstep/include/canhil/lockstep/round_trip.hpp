// canhil/lockstep/round_trip.hpp — the floor under every hand-over of the
// lockstep on this machine: a second process woken through a futex word in
// shared memory, which wakes the first back. No lockstep can hand the clock
// to a process and get it back faster (`canhil bench --part external`
// prints it beside the lockstep's own figures).
#pragma once

#include <optional>

#include "canhil/base/time.hpp"

namespace canhil::lockstep {

/// `rounds` round trips with a child process (on the same cores as the
/// calling thread; it goes with its parent): the mean wall time of one, or
/// nothing if the child could not be started or died on the way.
std::optional<Nanos> bare_round_trip(int rounds);

}  // namespace canhil::lockstep
