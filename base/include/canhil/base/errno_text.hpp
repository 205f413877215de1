// canhil/base/errno_text.hpp — the text of an errno value, for set-up errors
// that say what the system refused (sockets, namespaces, the bus's files).
#pragma once

#include <cstring>
#include <string>

namespace canhil {

inline std::string errno_text(int err) { return std::string(std::strerror(err)); }

}  // namespace canhil
