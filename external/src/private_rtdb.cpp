// RTDB keys of a run of its own (private_rtdb.hpp).
#include "canhil/external/private_rtdb.hpp"

#include <sys/ipc.h>
#include <sys/shm.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <set>
#include <string>

#include "canhil/base/process.hpp"

namespace canhil::external {
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
ino_t g_claim_namespace = 0;  // the IPC namespace the claim's id belongs to

// The IPC namespace this process is in (its /proc inode), 0 when unknown.
ino_t ipc_namespace() {
  struct stat st {};
  return ::stat("/proc/self/ns/ipc", &st) == 0 ? st.st_ino : 0;
}

// Every shared memory segment: f(id, its state). Other users' segments are
// seen too where the kernel has SHM_STAT_ANY (Linux 4.17: no read permission
// needed), elsewhere only those this process may read; a range held by one
// it cannot see is found by the claim (claim()).
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

struct Segments {
  std::set<unsigned> used;  // keys of `prefix` in use
  int removed = 0;          // orphans removed
};

// One look at the segments whose key starts with `prefix`: the keys in use,
// and, with `remove_orphans`, this user's segments that nobody is attached to
// and whose creator has ended removed (and not counted as used).
Segments sweep(unsigned prefix, bool remove_orphans) {
  Segments out;
  each_segment([&](int id, const shmid_ds& ds) {
    const auto key = static_cast<unsigned>(ds.shm_perm.__key);
    if (key >> 24 != prefix) return;
    const bool orphan = ds.shm_perm.uid == ::geteuid() && ds.shm_nattch == 0 && !process_alive(ds.shm_cpid);
    if (remove_orphans && orphan && ::shmctl(id, IPC_RMID, nullptr) == 0) {
      ++out.removed;
      return;
    }
    out.used.insert(key);
  });
  return out;
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
  g_claim_namespace = ipc_namespace();
  return true;
}

// The first range from the one of this process's id that no key of `used`
// is in, claimed.
unsigned free_range(unsigned prefix, const std::set<unsigned>& used) {
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
  const Segments segments = sweep(prefix, true);
  if (g_chosen_prefix == 0 && user_key() == nullptr) {
    g_chosen_prefix = prefix;
    set_key(free_range(prefix, segments.used));
  }
  return segments.removed;
}

void use_worker_rtdb_keys(int worker) {
  if (g_chosen_prefix != 0) {
    set_key(free_range(g_chosen_prefix, sweep(g_chosen_prefix, false).used));
    return;
  }
  const char* base = user_key();
  const long user = base != nullptr ? std::strtol(base, nullptr, 0) : 0;
  set_key(static_cast<unsigned>(user + ((worker + 1L) << 16)));
}

void release_private_rtdb_keys() {
  if (g_claim_id < 0 || g_claim_pid != ::getpid()) return;
  // In another IPC namespace (a worker of `match --external --jobs`) the id
  // would name another segment: the claim stays for the batch to sweep.
  if (ipc_namespace() == g_claim_namespace) ::shmctl(g_claim_id, IPC_RMID, nullptr);
  g_claim_id = -1;
}

int remove_orphan_rtdb_keys(unsigned prefix) { return sweep(prefix, true).removed; }

}  // namespace canhil::external
