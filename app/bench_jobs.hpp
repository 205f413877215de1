// app/bench_jobs.hpp — `canhil bench --part jobs`: match halves per
// wall-clock minute with `canhil match --jobs 2` against `--jobs 1`, in one
// run: the same halves of the ten-robot match (two_teams.toml or --config),
// played by the same worker processes canhil match uses. Target (issue 35,
// on these 2-core machines): at least 1.8x.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "canhil/frames/messages.hpp"

namespace canhil::app {

/// Prints both rates and the ratio; true when the target is met.
bool bench_jobs(const std::optional<std::string>& config, double seconds,
                const std::shared_ptr<const frames::MessageSet>& messages);

}  // namespace canhil::app
