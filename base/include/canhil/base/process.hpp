// canhil/base/process.hpp — whether a process is there, for the leftovers a
// process leaves when it is killed outright (a claim of RTDB keys, a worker's
// bus folder, a lockstep board) and for whoever must end with its owner (a
// bus's broker); and what a thread is doing (running or waiting for a CPU,
// asleep, stopped, ended), for whoever waits for it (the bus's broker for a
// reader, the lockstep conductor for a process).
#pragma once

#include <signal.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <dirent.h>
#include <fcntl.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

namespace canhil {

/// Whether process `pid` is there: answering signal 0, or there and not ours
/// to signal (EPERM). A pid of 0 or less is nobody.
inline bool process_alive(pid_t pid) noexcept { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

/// The state letter of thread `tid` of process `pid`, as
/// /proc/PID/task/TID/stat gives it: 'R' running or waiting for a CPU, 'S'
/// asleep, 'D' in an uninterruptible wait, 'T' stopped, 't' traced, 'Z' ended
/// and not yet reaped, ...; '?' when it cannot be read (gone). The letter is
/// the first field after the command's last ')' (a command may hold one).
inline char thread_state(pid_t pid, pid_t tid) noexcept {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/%d/task/%d/stat", static_cast<int>(pid), static_cast<int>(tid));
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return '?';
  char buffer[512];
  const ssize_t n = ::read(fd, buffer, sizeof buffer - 1);
  ::close(fd);
  if (n <= 0) return '?';
  buffer[n] = '\0';
  const char* close_paren = std::strrchr(buffer, ')');
  return close_paren != nullptr && close_paren[1] == ' ' ? close_paren[2] : '?';
}

/// Whether any thread of process `pid` is in one of `states` (thread_state's
/// letters). False for a process that is gone.
inline bool process_in_state(pid_t pid, const char* states) noexcept {
  if (pid <= 0) return false;
  char folder[48];
  std::snprintf(folder, sizeof folder, "/proc/%d/task", static_cast<int>(pid));
  DIR* tasks = ::opendir(folder);
  if (tasks == nullptr) return false;
  bool found = false;
  while (const dirent* t = ::readdir(tasks)) {
    char* end = nullptr;
    const long tid = std::strtol(t->d_name, &end, 10);
    if (end == t->d_name || *end != '\0') continue;
    const char state = thread_state(pid, static_cast<pid_t>(tid));
    if (state != '?' && std::strchr(states, state) != nullptr) {
      found = true;
      break;
    }
  }
  ::closedir(tasks);
  return found;
}

/// Whether any thread of process `pid` is runnable (thread_state 'R'): on a
/// CPU, or waiting for one on a busy machine. False for a process whose
/// threads sleep, are stopped or traced, or that is gone.
inline bool process_runnable(pid_t pid) noexcept { return process_in_state(pid, "R"); }

/// Whether process `pid` is held by the machine rather than by its own
/// choice: a thread runnable ('R', waiting for a CPU) or in an uninterruptible
/// wait ('D': a write to a busy disk, a page brought back in, a vfork). Such
/// a process comes back by itself; one whose threads all sleep ('S') waits
/// for something else (a stuck receiver, to the user-space bus's broker).
inline bool process_held_by_machine(pid_t pid) noexcept { return process_in_state(pid, "RD"); }

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
