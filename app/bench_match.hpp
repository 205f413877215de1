// app/bench_match.hpp — `canhil bench --part match`: the speed of whole
// matches on one core. Measured in one run, on the core the bench starts on:
//   physics alone   the five-robot scene's world stepped with nothing around
//                   it (the reference the targets are relative to)
//   five robots     five_robots.toml in virtual time, everything on
//   ten robots      a 5 v 5 match half (two_teams.toml or --config), everything
//                   on: referee, tally, every bus checked for FTT violations
// Targets (issue 15, on a machine where physics alone runs at 240x): five
// robots at least 180x and ten at least 80x, that is 0.75 and 1/3 of the
// physics-alone factor measured in the same run.
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
