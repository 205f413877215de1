// canhil/base/start_again.hpp — the one way canhil's programs put a library
// in LD_PRELOAD and start themselves again with it: canhil with the time shim
// (a run with the team's processes), canhil and canhil-hwcomm with the bus's
// preload (a kernel without CAN), a match's workers each on a bus of its own.
// Also how the list is composed for a program canhil starts (`canhil bus exec`).
//
// Header-only, libc and the standard library.
#pragma once

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace canhil {

/// The LD_PRELOAD value with `library` first and `existing` (a list as
/// LD_PRELOAD takes it, ':' between) after it, `library` not twice.
inline std::string preload_list(const std::string& library, const std::string& existing) {
  if (existing.empty()) return library;
  if ((":" + existing + ":").find(":" + library + ":") != std::string::npos) return existing;  // one of its entries
  return library + ":" + existing;
}

/// LD_PRELOAD of this process as it is now ("" when unset).
inline std::string current_preload() {
  const char* value = std::getenv("LD_PRELOAD");
  return value != nullptr ? value : "";
}

/// Puts `library` first in this process's LD_PRELOAD, for what it starts next
/// (itself again, or another program); nothing when it is there already.
inline void preload_first(const std::string& library) {
  setenv("LD_PRELOAD", preload_list(library, current_preload()).c_str(), 1);
}

/// The arguments this process was started with (/proc/self/cmdline).
inline std::vector<std::string> own_arguments() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::string> words;
  for (std::size_t at = 0; at < all.size();) {
    const std::size_t end = all.find('\0', at);
    words.push_back(all.substr(at, end - at));
    at = end == std::string::npos ? all.size() : end + 1;
  }
  return words;
}

/// Starts this program again (/proc/self/exe) with `arguments` and the
/// environment as it is now: the new image loads what LD_PRELOAD names.
/// Returns only when it could not, with errno.
inline int start_again(std::vector<std::string> arguments = own_arguments()) {
  std::vector<char*> argv;
  argv.reserve(arguments.size() + 1);
  for (std::string& w : arguments) argv.push_back(w.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  execv("/proc/self/exe", argv.data());
  return errno;
}

}  // namespace canhil
