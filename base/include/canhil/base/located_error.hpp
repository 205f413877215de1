// canhil/base/located_error.hpp — a set-up mistake at a place in a file.
//
// Every reader of a file canhil takes (a DBC, a world or scenario TOML, a
// layout description, the RTDB configuration) reports a mistake as one
// LocatedError, under its own name (DbcError, ConfigError, LayoutError,
// RtdbConfigError) so that a caller can catch one reader's. Its text is
// `FILE:LINE: FIELD: what is wrong; what to do`: `:LINE` left out when the
// line is 0 (the file as a whole), `FIELD: ` when there is no field.
#pragma once

#include <string>
#include <utility>

#include "canhil/base/setup_error.hpp"

namespace canhil {

class LocatedError : public SetupError {
 public:
  LocatedError(std::string file, int line, std::string field, const std::string& message)
      : SetupError(format(file, line, field, message)), file_(std::move(file)), line_(line), field_(std::move(field)) {}

  const std::string& file() const noexcept { return file_; }
  /// 1-based line of the mistake; 0 when it concerns the file as a whole.
  int line() const noexcept { return line_; }
  /// What in the file: a key (`ball.mass_kg`), an item's field (`VISION_INFO.ball`); "" when none.
  const std::string& field() const noexcept { return field_; }

  /// The text what() returns.
  static std::string format(const std::string& file, int line, const std::string& field, const std::string& message) {
    std::string out = file;
    if (line > 0) out += ':' + std::to_string(line);
    out += ": ";
    if (!field.empty()) out += field + ": ";
    return out + message;
  }

 private:
  std::string file_;
  int line_;
  std::string field_;
};

}  // namespace canhil
