// app/private_rtdb.cpp — private_rtdb.hpp.
#include "private_rtdb.hpp"

#include <sys/ipc.h>
#include <sys/shm.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <set>
#include <string>

namespace canhil::app {
namespace {

constexpr unsigned kRange = 0x100;  // keys of one process: two sets of up to 64 agents, with room

// The prefix canhil chose this process's keys with (0: the user set RTDB_KEY, or none chosen yet).
unsigned g_chosen_prefix = 0;

// Whether the process `pid` is there (or there and not ours to signal).
bool alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// Every shared memory segment this process may read: f(id, its state).
template <typename F>
void each_segment(F&& f) {
  shm_info info{};
  const int highest = ::shmctl(0, SHM_INFO, reinterpret_cast<shmid_ds*>(&info));
  for (int index = 0; index <= highest; ++index) {
    shmid_ds ds{};
    const int id = ::shmctl(index, SHM_STAT, &ds);
    if (id >= 0) f(id, ds);  // else a free index, or not ours to read
  }
}

unsigned key_of(const shmid_ds& ds) { return static_cast<unsigned>(ds.shm_perm.__key); }

int remove_orphans(unsigned prefix) {
  int removed = 0;
  each_segment([&](int id, const shmid_ds& ds) {
    if (key_of(ds) >> 24 != prefix || ds.shm_perm.uid != ::geteuid() || ds.shm_nattch != 0 || alive(ds.shm_cpid)) {
      return;
    }
    if (::shmctl(id, IPC_RMID, nullptr) == 0) ++removed;
  });
  return removed;
}

// The first range from the one of this process's id that no segment is in.
unsigned free_range(unsigned prefix) {
  std::set<unsigned> used;
  each_segment([&](int, const shmid_ds& ds) {
    if (key_of(ds) >> 24 == prefix) used.insert(key_of(ds));
  });
  const unsigned own = static_cast<unsigned>(::getpid()) & 0xFFFFu;
  for (unsigned k = 0; k <= 0xFFFFu; ++k) {
    const unsigned base = (prefix << 24) | (((own + k) & 0xFFFFu) << 8);
    const auto next = used.lower_bound(base);
    if (next == used.end() || *next >= base + kRange) return base;
  }
  return (prefix << 24) | (own << 8);  // every range taken: its own, and the RTDB says what is wrong
}

void set_key(unsigned key) { ::setenv("RTDB_KEY", std::to_string(key).c_str(), 1); }

}  // namespace

int use_private_rtdb_keys(unsigned prefix) {
  const int removed = remove_orphans(prefix);
  if (g_chosen_prefix == 0 && std::getenv("RTDB_KEY") == nullptr) {
    g_chosen_prefix = prefix;
    set_key(free_range(prefix));
  }
  return removed;
}

void use_worker_rtdb_keys(int worker) {
  if (g_chosen_prefix != 0) {
    set_key(free_range(g_chosen_prefix));
    return;
  }
  const char* base = std::getenv("RTDB_KEY");
  const long user = base != nullptr ? std::strtol(base, nullptr, 0) : 0;
  set_key(static_cast<unsigned>(user + ((worker + 1L) << 16)));
}

}  // namespace canhil::app
