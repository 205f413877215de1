// app/bench_wire.hpp — `canhil bench --part wire`: what the timed wire costs.
//   - the five-robot virtual-time run with every bus on a timed wire at
//     1 Mbit/s against the same run with instant buses, CPU time, runs in
//     turns; target (issue 54): at least 0.9 of the instant run's speed;
//   - the wire model alone (wire::WireBus): frames through arbitration,
//     delivery and error confinement per second of CPU, for scale;
//   - the user-space bus's delivery against the model's ideal end of frame
//     in real time (target: p99 at most 100 us): not measured while the
//     broker does not time frames (docs/wire.md).
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
