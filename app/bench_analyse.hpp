// app/bench_analyse.hpp — `canhil bench --part analyse`: how long
// `canhil timing --analyse` takes on a 200-message set, everything included
// (frame times, the FTT schedule over its cycle, every bound, the what-if
// searches), for an FTT-CAN set (the TM, 31 synchronous messages, 168
// sporadic) and a native one (200 messages), both drawn from a fixed seed.
// Target (issue 34): at most 50 ms each, the median of several runs.
#pragma once

namespace canhil::app {

/// Prints the times and the target; true when it is met.
bool bench_analyse();

}  // namespace canhil::app
