// canhil/wire/report.hpp — a bus's state in words, for run summaries and
// `canhil bus list`: its bit rate, load, frames and errors, and every
// controller with something to tell (errors, a state other than
// error-active, bus-offs, restarts, refused frames).
#pragma once

#include <string>

#include "canhil/wire/wire_bus.hpp"

namespace canhil::wire {

/// Lines of text, each starting with `indent`, the last ending in a newline.
std::string report(const WireBus& bus, const std::string& indent);

}  // namespace canhil::wire
