// canhil/base/process.hpp — whether a process is there, for the leftovers a
// process leaves when it is killed outright (a claim of RTDB keys, a worker's
// bus folder, a lockstep board) and for whoever must end with its owner (a
// bus's broker).
#pragma once

#include <signal.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace canhil {

/// Whether process `pid` is there: answering signal 0, or there and not ours
/// to signal (EPERM). A pid of 0 or less is nobody.
inline bool process_alive(pid_t pid) noexcept { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

/// Calls `left(path)` for each entry of `folder` that a process of this user
/// left behind when it ended without removing it: named `prefix`, then the
/// pid of the process that made it, then `after` ('\0': nothing more), owned
/// by this user, its pid no longer running. The entry itself is not followed
/// (a symbolic link is one). A folder that cannot be read has none.
template <class Left>
void for_each_left_by_the_dead(const std::filesystem::path& folder, const std::string& prefix, char after,
                               Left&& left) {
  std::error_code failed;
  for (const auto& entry : std::filesystem::directory_iterator(folder, failed)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
    if (end == name.c_str() + prefix.size() || *end != after || pid <= 0) continue;
    struct stat st {};
    if (::lstat(entry.path().c_str(), &st) != 0 || st.st_uid != ::getuid()) continue;
    if (!process_alive(static_cast<pid_t>(pid))) left(entry.path());
  }
}

}  // namespace canhil
