// app/dbc_choice.hpp — which message set a command uses.
#pragma once

#include <optional>
#include <string>

#include "canhil/frames/dbc.hpp"

namespace canhil::app {

/// --dbc FILE if given, else the shipped message set (or CANHIL_DBC).
inline frames::Database load_chosen_dbc(const std::optional<std::string>& dbc) {
  return frames::load_dbc(dbc ? std::filesystem::path(*dbc) : frames::default_dbc_path());
}

}  // namespace canhil::app
