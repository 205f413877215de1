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
// The range's last key, which the RTDB never uses (it takes the first 128):
// a process that holds a range holds a segment there from the moment it
// chooses it, so that no other process takes the range before the RTDB's
// segments are there.
constexpr unsigned kClaimKey = kRange - 1;

// The prefix canhil chose this process's keys with (0: the user set RTDB_KEY, or none chosen yet).
unsigned g_chosen_prefix = 0;
// The claim's segment, and the process that made it (a worker forked later does not remove it).
int g_claim_id = -1;
pid_t g_claim_pid = 0;

// Whether the process `pid` is there (or there and not ours to signal).
bool alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// Every shared memory segment: f(id, its state). Other users' segments are
// seen too (SHM_STAT_ANY: without the read permission) where the kernel has
// it (4.17), and otherwise only those
// this process may read; a range held by one it cannot see is found by the
// claim (claim()).
template <typename F>
void each_segment(F&& f) {
  shm_info info{};
  const int highest = ::shmctl(0, SHM_INFO, reinterpret_cast<shmid_ds*>(&info));
  static int stat = SHM_STAT_ANY;
  for (int index = 0; index <= highest; ++index) {
    shmid_ds ds{};
    int id = ::shmctl(index, stat, &ds);
    if (id < 0 && errno == EINVAL && stat == SHM_STAT_ANY) {  // a free index, or a kernel without it
      id = ::shmctl(index, SHM_STAT, &ds);
      if (id >= 0) stat = SHM_STAT;  // a kernel without it
    }
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

// Takes the range at `base` for this process: false if another has it. A
// claim the system refuses for want of room (a full segment table) leaves
// the range unclaimed but taken: the RTDB says what is wrong if it cannot
// make its own segments either.
bool claim(unsigned base) {
  const int id = ::shmget(static_cast<key_t>(base + kClaimKey), 1, IPC_CREAT | IPC_EXCL | 0600);
  if (id < 0) return errno != EEXIST && errno != EACCES;
  g_claim_id = id;
  g_claim_pid = ::getpid();
  return true;
}

// The first range from the one of this process's id that no segment is in,
// claimed.
unsigned free_range(unsigned prefix) {
  std::set<unsigned> used;
  each_segment([&](int, const shmid_ds& ds) {
    if (key_of(ds) >> 24 == prefix) used.insert(key_of(ds));
  });
  const unsigned own = static_cast<unsigned>(::getpid()) & 0xFFFFu;
  for (unsigned k = 0; k <= 0xFFFFu; ++k) {
    const unsigned base = (prefix << 24) | (((own + k) & 0xFFFFu) << 8);
    const auto next = used.lower_bound(base);
    if ((next == used.end() || *next >= base + kRange) && claim(base)) return base;
  }
  return (prefix << 24) | (own << 8);  // every range taken: its own, and the RTDB says what is wrong
}

// The key the user set, if any: an empty RTDB_KEY is none, as the RTDB reads it.
const char* user_key() {
  const char* key = std::getenv("RTDB_KEY");
  return key != nullptr && *key != '\0' ? key : nullptr;
}

void set_key(unsigned key) { ::setenv("RTDB_KEY", std::to_string(key).c_str(), 1); }

}  // namespace

int use_private_rtdb_keys(unsigned prefix) {
  const int removed = remove_orphans(prefix);
  if (g_chosen_prefix == 0 && user_key() == nullptr) {
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
  const char* base = user_key();
  const long user = base != nullptr ? std::strtol(base, nullptr, 0) : 0;
  set_key(static_cast<unsigned>(user + ((worker + 1L) << 16)));
}

void release_private_rtdb_keys() {
  if (g_claim_id < 0 || g_claim_pid != ::getpid()) return;
  ::shmctl(g_claim_id, IPC_RMID, nullptr);
  g_claim_id = -1;
}

}  // namespace canhil::app
