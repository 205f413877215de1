// app/bench_wire.hpp — `canhil bench --part wire`: what the timed wire costs.
//   - the five-robot virtual-time run with every bus on a timed wire at
//     1 Mbit/s against the same run with instant buses, CPU time, runs in
//     turns; target (issue 54): at least 0.9 of the instant run's speed;
//   - the user-space bus's delivery against the model's ideal end of frame
//     in real time, read by a reader asleep in recv and by one awake when the
//     frame is due (target, for the latter: p99 at most 100 us), beside the
//     instant bus's whole hop. The model alone: build/plain/bench/wire_bench.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "canhil/frames/messages.hpp"

namespace canhil::app {

/// Prints the figures and the targets; true when every measured target is met.
bool bench_wire(const std::optional<std::string>& config, double seconds,
                const std::shared_ptr<const frames::MessageSet>& messages);

}  // namespace canhil::app
