// canhil/physics/config.hpp — the world's parameters from a TOML file.
//
// Every value is optional: what a file leaves out keeps its default (the
// reference figures). A mistake is a ConfigError whose text is
// `FILE:LINE: FIELD: what is wrong; what to do`, e.g.
// `world.toml:12: ball.mass_kg: must be greater than 0, got -1`.
// Unknown fields are mistakes too (with the nearest known name suggested),
// so a misspelt key never silently keeps a default. The shipped
// physics/config/world.toml lists every field with its default.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "canhil/base/located_error.hpp"
#include "canhil/physics/params.hpp"

namespace canhil::physics {

/// A mistake in a world (or scenario) file: `FILE:LINE: FIELD: what is wrong`.
class ConfigError : public LocatedError {
 public:
  ConfigError(std::string file, int line, std::string field, const std::string& message)
      : LocatedError(std::move(file), line, std::move(field), message) {}
};

/// `other_tables`: top-level tables another layer reads from the same file
/// (a scenario's [run]); they are not reported as unknown.
WorldParams parse_world_params(std::string_view toml_text, const std::string& file_name,
                               const std::vector<std::string>& other_tables = {});
/// Throws ConfigError (also when the file cannot be read).
WorldParams load_world_params(const std::filesystem::path& path, const std::vector<std::string>& other_tables = {});
/// The whole file as text; throws ConfigError naming it when it cannot be read.
std::string read_config_file(const std::filesystem::path& path);

}  // namespace canhil::physics
