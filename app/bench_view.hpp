// app/bench_view.hpp — `canhil bench --part view`: the five-robot
// virtual-time run with a page connected to its viewer (a WebSocket client
// taking every state, as a browser would) against the same run without one,
// in the same process and run. Target: the viewer keeps at least 90 % of the
// real-time factor.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "canhil/frames/messages.hpp"

namespace canhil::app {

/// Prints both factors and their ratio; true when the ratio is at least 0.9.
bool bench_view(const std::optional<std::string>& config, double seconds,
                const std::shared_ptr<const frames::MessageSet>& messages);

}  // namespace canhil::app
