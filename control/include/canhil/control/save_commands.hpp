// canhil/control/save_commands.hpp — named saves of a running world, in one
// folder: a scenario (NAME.toml, the format `canhil run --config` reads) or a
// snapshot (NAME.world, the format of --save-world / --restore-world).
//
//   save {name, kind}     kind "scenario" or "snapshot"; replaces one of that name
//   saves                 [{name, kind}] in the folder
//   load {name, kind}     puts the running world into it (same robots and obstacles)
//
// A name is 1..64 letters, digits, '-', '_' or '.', not starting with '.':
// nothing outside the folder can be named.
#pragma once

#include <filesystem>

#include "canhil/control/commands.hpp"

namespace canhil::control {

/// Adds them to `commands`; `session` must outlive it. The folder is made at the first save.
void add_save_commands(Commands& commands, emulator::Session& session, const std::filesystem::path& folder);

/// The saves in `folder`: (name, "scenario" | "snapshot"), sorted.
std::vector<std::pair<std::string, std::string>> list_saves(const std::filesystem::path& folder);

}  // namespace canhil::control
