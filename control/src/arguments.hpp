// control/src/arguments.hpp — reading a command's arguments: each mistake a
// SetupError that says what to send (the reply's "error").
#pragma once

#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "canhil/base/setup_error.hpp"

namespace canhil::control {

using nlohmann::json;

// Positions must be on or near the field: nothing a hostile number can put far away.
constexpr double kMaxCoordinateM = 50.0;
constexpr double kMaxSpeedMps = 40.0;

inline double number(const json& request, const char* key, double low, double high) {
  const auto it = request.find(key);
  if (it == request.end()) throw SetupError(std::string("give \"") + key + "\" (a number)");
  if (!it->is_number()) throw SetupError(std::string("\"") + key + "\" must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v) || v < low || v > high) {
    throw SetupError(std::string("\"") + key + "\" must be a number from " + std::to_string(low) + " to " +
                     std::to_string(high));
  }
  return v;
}

inline double number_or(const json& request, const char* key, double fallback, double low, double high) {
  return request.contains(key) ? number(request, key, low, high) : fallback;
}

inline std::size_t index(const json& request, const char* key) {
  const auto it = request.find(key);
  if (it == request.end() || !it->is_number_unsigned()) {
    throw SetupError(std::string("give \"") + key + "\" as a whole number, 0 or more");
  }
  const auto v = it->get<std::uint64_t>();
  if (v > 1000) throw SetupError(std::string("\"") + key + "\" is out of range");
  return static_cast<std::size_t>(v);
}

inline std::string text(const json& request, const char* key, std::size_t longest = 200) {
  const auto it = request.find(key);
  if (it == request.end() || !it->is_string()) throw SetupError(std::string("give \"") + key + "\" as a text");
  std::string v = it->get<std::string>();
  if (v.empty() || v.size() > longest) throw SetupError(std::string("\"") + key + "\" is empty or too long");
  return v;
}

}  // namespace canhil::control
