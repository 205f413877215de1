// canhil/physics/config_toml.hpp — the world's tables read from a TOML
// document another layer has parsed already (a scenario: one parse for the
// world and its [run]). Needs toml++ (the includer links it).
#pragma once

#include <toml++/toml.h>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/physics/params.hpp"

namespace canhil::physics {

/// The document; ConfigError naming the file and line when it is not valid TOML.
toml::table parse_toml(std::string_view toml_text, const std::string& file_name);
/// parse_world_params on a parsed document.
WorldParams read_world_params(const toml::table& root, const std::string& file_name,
                              const std::vector<std::string>& other_tables = {});

}  // namespace canhil::physics
