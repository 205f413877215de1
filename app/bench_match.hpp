// app/bench_match.hpp — `canhil bench --part match`: the speed of whole
// matches on one core. Measured in one run, on the core the bench starts on:
//   physics alone   the five-robot scene's world stepped with nothing around
//                   it, and the ten-robot one's (for scale)
//   five robots     five_robots.toml in virtual time, everything on
//   ten robots      a 5 v 5 match half (two_teams.toml or --config), everything
//                   on: referee, tally, every bus checked for FTT violations
// Targets (issue 15, on one core of these machines, where the same five-robot
// run of the code the issue measured was 130x): five robots at least 180x and
// ten at least 80x. bench/against_base.sh builds that code and measures the
// targets against it in the same run, which takes the machine's speed out.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "canhil/frames/messages.hpp"

namespace canhil::app {

/// Prints the factors and the targets; true when both are met.
bool bench_match(const std::optional<std::string>& config, double seconds,
                 const std::shared_ptr<const frames::MessageSet>& messages);

}  // namespace canhil::app
