// laptop/src/cli_numbers.hpp — strict number parsing for the laptop programs' options.
#pragma once

#include <cerrno>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace canhil::laptop {

/// The whole of `text` as a number, or std::invalid_argument naming `option`.
inline double parse_number(const std::string& option, const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno != 0) {
    throw std::invalid_argument(option + " takes a number, got \"" + text + "\"");
  }
  return v;
}

}  // namespace canhil::laptop
