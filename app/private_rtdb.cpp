// app/private_rtdb.cpp — private_rtdb.hpp.
#include "private_rtdb.hpp"

#include <sys/ipc.h>
#include <sys/shm.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <string>

namespace canhil::app {
namespace {

// Whether the process `pid` is there (or there and not ours to signal).
bool alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

int remove_orphans(unsigned prefix) {
  shm_info info{};
  const int highest = ::shmctl(0, SHM_INFO, reinterpret_cast<shmid_ds*>(&info));
  int removed = 0;
  for (int index = 0; index <= highest; ++index) {
    shmid_ds ds{};
    const int id = ::shmctl(index, SHM_STAT, &ds);
    if (id < 0) continue;  // a free index, or not ours to read
    const auto key = static_cast<unsigned>(ds.shm_perm.__key);
    if (key >> 24 != prefix || ds.shm_perm.uid != ::geteuid() || ds.shm_nattch != 0 || alive(ds.shm_cpid)) continue;
    if (::shmctl(id, IPC_RMID, nullptr) == 0) ++removed;
  }
  return removed;
}

}  // namespace

int use_private_rtdb_keys(unsigned prefix) {
  const int removed = remove_orphans(prefix);
  if (std::getenv("RTDB_KEY") == nullptr) {
    const unsigned key = (prefix << 24) + ((static_cast<unsigned>(::getpid()) & 0xFFFFu) << 8);
    ::setenv("RTDB_KEY", std::to_string(key).c_str(), 1);
  }
  return removed;
}

}  // namespace canhil::app
