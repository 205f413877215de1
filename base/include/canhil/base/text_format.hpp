// canhil/base/text_format.hpp — printf's formats into a std::string of the
// length the text needs (a message built from measured values and a team's
// names: the solver's reports, canhil test's verdicts, a run's limits).
#pragma once

#include <cstdarg>
#include <cstdio>
#include <string>

namespace canhil {

/// `format` with `args` (vprintf's rules), whole however long.
inline std::string vformat_text(const char* format, va_list args) {
  va_list again;
  va_copy(again, args);
  char small[256];
  const int n = std::vsnprintf(small, sizeof small, format, args);
  std::string out;
  if (n < 0) {
    out = format;  // a format the C library refuses: the format itself, rather than nothing
  } else if (static_cast<std::size_t>(n) < sizeof small) {
    out.assign(small, static_cast<std::size_t>(n));
  } else {
    out.resize(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), format, again);
    out.resize(static_cast<std::size_t>(n));
  }
  va_end(again);
  return out;
}

/// `format` with the arguments that follow (printf's rules), whole however long.
inline std::string format_text(const char* format, ...) __attribute__((format(printf, 1, 2)));
inline std::string format_text(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::string out = vformat_text(format, args);
  va_end(args);
  return out;
}

}  // namespace canhil
