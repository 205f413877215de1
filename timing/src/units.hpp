// timing/src/units.hpp — the small conversions every report of timing/ uses
// (internal: one copy for the unity build and for people).
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

#include "canhil/base/time.hpp"

namespace canhil::timing::units {

inline double us(Nanos t) { return std::chrono::duration<double, std::micro>(t).count(); }
inline double ms(Nanos t) { return std::chrono::duration<double, std::milli>(t).count(); }

/// ceil(a / b) for b > 0; 0 when a <= 0.
inline std::int64_t ceil_div(Nanos a, Nanos b) noexcept {
  return a.count() <= 0 ? 0 : (a.count() + b.count() - 1) / b.count();
}

/// 0x010 (standard) or 0x18FF0001 (extended).
inline std::string id_text(std::uint32_t id, bool extended) {
  char b[16];
  std::snprintf(b, sizeof b, extended ? "0x%08X" : "0x%03X", id);
  return b;
}

}  // namespace canhil::timing::units
