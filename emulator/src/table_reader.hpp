// emulator/src/table_reader.hpp — what scenario.cpp and scenario_teams.cpp
// share beyond the TableReader (canhil/emulator/table_reader.hpp): the tables
// a team may give again, and [[teams]]. Not installed.
#pragma once

#include <toml++/toml.h>

#include <string>
#include <vector>

#include "canhil/emulator/scenario.hpp"
#include "canhil/emulator/table_reader.hpp"

namespace canhil::emulator::detail {

using ::canhil::emulator::TableReader;

// The scenario's tables a team may give again (scenario.cpp).
void read_laptop(const TableReader& r, LaptopSide& l);
void read_external(const TableReader& r, ExternalSide& e);
const std::vector<std::string>& laptop_fields();
const std::vector<std::string>& external_fields();

/// [[teams]] (scenario_teams.cpp): the teams, their robots placed into
/// s.world.robots (refused next to [[robots]]), their interfaces, agents and
/// coach players. False when the file has no teams.
bool read_teams(const toml::table& root, const std::string& file, Scenario& s);
/// The teams' checks and defaults, for files and code alike (complete()).
void complete_teams(Scenario& s);

}  // namespace canhil::emulator::detail
