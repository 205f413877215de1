// canhil/emulator/scenario.hpp — a scenario file: the world (every table of
// physics/config/world.toml: field, ball, robot model, [[robots]] with their
// start poses, [[obstacles]], ball_start) plus a [run] table for what `canhil
// run` does with it:
//
//   [run]
//   duration_s = 20                  # virtual-time runs; real time runs until Ctrl-C
//   seed = 1                         # fault draws
//   kick_power = 40                  # the reference agent's kick, 0..max_power
//   interfaces = ["vcan0"]           # one per robot; default vcan0, vcan1, ...
//   agents = [1]                     # one per robot, 1..6; default 1, 2, ...
//   faults = ["drop:M4_1:0.1"]       # see can_nodes/fault.hpp
//
// Mistakes are physics::ConfigError: `FILE:LINE: run.FIELD: what; what to do`.
// The shipped scenarios are in emulator/scenarios/.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "canhil/can_nodes/fault.hpp"
#include "canhil/emulator/virtual_run.hpp"
#include "canhil/physics/params.hpp"

namespace canhil::emulator {

struct Scenario {
  physics::WorldParams world;
  double duration_s = 20;
  std::uint64_t seed = 1;
  int kick_power = 40;
  std::vector<std::string> interfaces;  ///< one per robot after loading
  std::vector<int> agents;              ///< one per robot after loading
  std::vector<can_nodes::FaultRule> faults;
};

Scenario parse_scenario(std::string_view toml_text, const std::string& file_name);
Scenario load_scenario(const std::filesystem::path& path);
/// What a virtual-time run of the scenario takes (world log off).
VirtualRunConfig virtual_run_config(const Scenario& scenario, std::shared_ptr<const frames::MessageSet> messages);

}  // namespace canhil::emulator
