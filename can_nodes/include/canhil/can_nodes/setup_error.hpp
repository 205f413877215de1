// canhil/can_nodes/setup_error.hpp — a set-up mistake the user can fix.
#pragma once

#include <stdexcept>

namespace canhil::can_nodes {

/// A set-up mistake (no CAN in the kernel, no such interface, a schedule that
/// does not fit). The message says what is wrong and what to do.
class SetupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace canhil::can_nodes
