// tests/support/error_of.hpp — the message of the error a piece of code
// throws, for tests that check what a mistake says.
#pragma once

#include <string>

#include "canhil/base/setup_error.hpp"

namespace canhil::test {

/// What `f()` throws as an `Error` (a SetupError unless told), or "(no error)".
template <class Error = SetupError, class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace canhil::test
