// canhil/base/setup_error.hpp — "you gave me something wrong".
//
// Every set-up mistake a user can fix derives from SetupError: a bad DBC, a
// bad configuration or scenario, a fault rule that does not parse, no such
// interface, a schedule that does not fit, a command-line mistake. The message
// says what is wrong and what to do; `main` catches this one type. Broken
// invariants are CANHIL_DEMAND (base/demand.hpp); bad traffic is counted.
#pragma once

#include <stdexcept>

namespace canhil {

class SetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace canhil
