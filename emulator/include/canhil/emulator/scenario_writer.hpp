// canhil/emulator/scenario_writer.hpp — a running world saved as a scenario
// file, the TOML `canhil run --config` reads: the viewer's "save as scenario".
#pragma once

#include <string>

#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/session.hpp"

namespace canhil::emulator {

/// The scenario with the world as `now` has it: [run], [coach], [[robots]],
/// [[obstacles]] and [ball_start] written from the run; every other table of
/// the file the scenario came from (physics, [laptop], [external]) kept as it
/// was, with the laptop's paths made absolute so the file works from anywhere.
/// Loading the result gives the same scenario, placed where `now` has things.
std::string scenario_toml(const Scenario& scenario, const WorldSnapshot& now);

}  // namespace canhil::emulator
