// errno_text.hpp — the text of an errno value, for the SocketCAN code's
// set-up errors (can_nodes/src only).
#pragma once

#include <cstring>
#include <string>

namespace canhil::can_nodes::detail {

inline std::string errno_text(int err) { return std::string(std::strerror(err)); }

}  // namespace canhil::can_nodes::detail
