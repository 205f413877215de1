// The time shim's core: attaching to the board, slots, the virtual clock, the
// blocking primitive and the emulated timerfds (shim_core.hpp).
#include "shim_core.hpp"

#include <fcntl.h>
#include <linux/futex.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

#include "canhil/lockstep/shim_hook.h"

namespace canhil::lockstep::shim {
namespace {

Board* g_board = nullptr;
std::atomic<bool> g_detached{false};
bool g_conducting = false;  // in canhil's own process: the clocks only
thread_local Slot* t_slot = nullptr;
pthread_key_t g_thread_key;

std::int64_t wall_ns() noexcept {
  static const auto real = next_symbol<int (*)(clockid_t, timespec*)>("clock_gettime");
  timespec ts{};
  real(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * kSecond + ts.tv_nsec;
}

void announce_change() noexcept {
  g_board->changes.fetch_add(1, std::memory_order_release);
  futex(&g_board->changes, FUTEX_WAKE, INT_MAX, nullptr);
}

void copy_text(char* to, std::size_t size, const char* from) noexcept {
  std::size_t i = 0;
  for (; i + 1 < size && from[i] != '\0'; ++i) to[i] = from[i];
  to[i] = '\0';
}

// Fills a slot this process holds for thread `tid`, running; the state is
// set last, so the conductor never sees half a slot.
void fill(Slot& s, std::int32_t tid) noexcept {
  s.tid.store(tid);
  char name[17] = {};
  prctl(PR_GET_NAME, name);
  copy_text(s.name, sizeof s.name, name);
  copy_text(s.what, sizeof s.what, "starting");
  s.frames_sent.store(0);
  s.blocks.store(0);
  s.busy_wall_ns.store(0);
  s.running_since_wall_ns.store(wall_ns());
  s.wake_at_ns.store(kNoWake);
  s.signal_wait.store(0);
  s.join_tid.store(0);
  s.seen_epoch.store(0);
  s.state.store(static_cast<std::uint32_t>(SlotState::kRunning), std::memory_order_release);
}

Slot* claim(std::int32_t tid) noexcept {
  const auto pid = static_cast<std::int32_t>(getpid());
  for (Slot& s : g_board->slots) {
    std::int32_t free_pid = 0;
    if (!s.pid.compare_exchange_strong(free_pid, pid)) continue;
    fill(s, tid);
    return &s;
  }
  preload::say(kWho, "all %zu slots of the board are taken: thread %d runs unseen by canhil's clock", kMaxSlots, tid);
  return nullptr;
}

void thread_ended(void* slot) noexcept { release(static_cast<Slot*>(slot)); }

// Goes on in real time: canhil ended its run (released the board: expected,
// said nothing) or died without doing so (said on stderr).
void detach() noexcept {
  if (!g_detached.exchange(true) && g_board->released.load(std::memory_order_acquire) == 0) {
    preload::say(kWho, "canhil (pid %d) is gone: this process goes on in real time", g_board->conductor_pid);
  }
}

bool released() noexcept { return g_board->released.load(std::memory_order_acquire) != 0; }

bool conductor_gone() noexcept { return kill(g_board->conductor_pid, 0) == -1 && errno == ESRCH; }

void account_busy(Slot& slot) noexcept {
  const std::int64_t since = slot.running_since_wall_ns.load(std::memory_order_relaxed);
  if (since > 0) slot.busy_wall_ns.fetch_add(static_cast<std::uint64_t>(wall_ns() - since), std::memory_order_relaxed);
}

void mark_running(Slot& slot) noexcept {
  slot.running_since_wall_ns.store(wall_ns(), std::memory_order_relaxed);
  slot.state.store(static_cast<std::uint32_t>(SlotState::kRunning), std::memory_order_release);
}

void mark_gone_all_of_this_process() noexcept {
  const auto pid = static_cast<std::int32_t>(getpid());
  for (Slot& s : g_board->slots) {
    if (s.pid.load() == pid) s.state.store(static_cast<std::uint32_t>(SlotState::kGone), std::memory_order_release);
  }
  announce_change();
}

// The slots an earlier image of this process left before it called exec (a
// shell that ran `exec PROGRAM`, a program that re-executes itself): their
// threads are gone or are this one. The new program takes over the first of
// them in place and frees the rest; the process never looks absent to the
// conductor, which might otherwise start the run in that gap.
Slot* take_over_earlier_image(std::int32_t tid) noexcept {
  const auto pid = static_cast<std::int32_t>(getpid());
  Slot* mine = nullptr;
  for (Slot& s : g_board->slots) {
    if (s.pid.load() != pid) continue;
    if (mine == nullptr && s.state.load(std::memory_order_acquire) != static_cast<std::uint32_t>(SlotState::kFree)) {
      mine = &s;
      s.state.store(static_cast<std::uint32_t>(SlotState::kRunning), std::memory_order_release);
      fill(s, tid);
      continue;
    }
    s.state.store(static_cast<std::uint32_t>(SlotState::kFree), std::memory_order_release);
    s.pid.store(0, std::memory_order_release);
  }
  return mine != nullptr ? mine : claim(tid);
}

void after_fork_in_child() noexcept {
  if (g_board == nullptr) return;
  t_slot = claim(static_cast<std::int32_t>(gettid()));
  pthread_setspecific(g_thread_key, t_slot);
}

__attribute__((constructor)) void attach() {
  const char* name = std::getenv(kBoardVariable);
  if (name == nullptr || *name == '\0') return;
  const int fd = shm_open(name, O_RDWR | O_CLOEXEC, 0);
  if (fd < 0) {
    preload::say(kWho, "cannot open canhil's board %s (%s): running in real time", name, std::strerror(errno));
    return;
  }
  void* mapped = mmap(nullptr, sizeof(Board), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (mapped == MAP_FAILED) {
    preload::say(kWho, "cannot map canhil's board %s (%s): running in real time", name, std::strerror(errno));
    return;
  }
  auto* board = static_cast<Board*>(mapped);
  if (board->magic != kMagic || board->version != kVersion) {
    preload::say(kWho, "%s is not a canhil lockstep board of version %u (this shim's): running in real time", name,
                 kVersion);
    munmap(mapped, sizeof(Board));
    return;
  }
  pthread_key_create(&g_thread_key, thread_ended);
  pthread_atfork(nullptr, nullptr, after_fork_in_child);
  g_board = board;
  t_slot = take_over_earlier_image(static_cast<std::int32_t>(gettid()));
  pthread_setspecific(g_thread_key, t_slot);
  announce_change();
}

__attribute__((destructor)) void leave() {
  if (g_board != nullptr) mark_gone_all_of_this_process();
}

// Emulated timerfds.
struct Timer {
  int fd = -1;
  clockid_t clock = CLOCK_MONOTONIC;
  std::int64_t next_ns = kNoWake;  // virtual
  std::int64_t interval_ns = 0;
};
std::array<Timer, 64> g_timers;
std::atomic_flag g_timers_lock = ATOMIC_FLAG_INIT;

Timer* find_timer(int fd) noexcept {
  for (Timer& t : g_timers) {
    if (t.fd == fd) return &t;
  }
  return nullptr;
}

void drain(int fd) noexcept {
  static const auto real_read = next_symbol<ssize_t (*)(int, void*, size_t)>("read");
  static const auto real_poll = next_symbol<int (*)(pollfd*, nfds_t, int)>("poll");
  pollfd p{fd, POLLIN, 0};
  if (real_poll(&p, 1, 0) == 1) {
    std::uint64_t ignored = 0;
    [[maybe_unused]] const auto r = real_read(fd, &ignored, sizeof ignored);
  }
}

// Threads started through the shim: pthread_t -> its slot, for pthread_join.
struct Started {
  pthread_t thread{};
  Slot* slot = nullptr;
};
std::array<Started, 256> g_started;
std::atomic_flag g_started_lock = ATOMIC_FLAG_INIT;

}  // namespace

Board* board() noexcept {
  if (g_detached.load(std::memory_order_relaxed) || g_board == nullptr) return nullptr;
  if (released()) {
    detach();
    return nullptr;
  }
  return g_board;
}

std::int64_t now_ns() noexcept { return g_board->now_ns.load(std::memory_order_acquire); }

bool virtual_reading(clockid_t clock, std::int64_t& ns) noexcept {
  const Board* b = board();
  if (b == nullptr) return false;
  switch (clock) {
    case CLOCK_REALTIME:
    case CLOCK_REALTIME_COARSE:
    case CLOCK_TAI:
      ns = b->realtime_base_ns + now_ns();
      return true;
    case CLOCK_MONOTONIC:
    case CLOCK_MONOTONIC_RAW:
    case CLOCK_MONOTONIC_COARSE:
    case CLOCK_BOOTTIME:
      ns = b->monotonic_base_ns + now_ns();
      return true;
    default:
      return false;
  }
}

std::int64_t to_virtual(clockid_t clock, std::int64_t absolute_ns) noexcept {
  const bool realtime = clock == CLOCK_REALTIME || clock == CLOCK_REALTIME_COARSE || clock == CLOCK_TAI;
  return absolute_ns - (realtime ? g_board->realtime_base_ns : g_board->monotonic_base_ns);
}

bool conducting() noexcept { return g_conducting; }

Slot* my_slot() noexcept {
  if (board() == nullptr || g_conducting) return nullptr;
  if (t_slot == nullptr) {
    t_slot = claim(static_cast<std::int32_t>(gettid()));
    pthread_setspecific(g_thread_key, t_slot);
  }
  return t_slot;
}

Slot* claim_for_new_thread() noexcept { return board() == nullptr ? nullptr : claim(0); }

void adopt(Slot* slot) noexcept {
  if (slot == nullptr) return;
  slot->tid.store(static_cast<std::int32_t>(gettid()));
  t_slot = slot;
  pthread_setspecific(g_thread_key, slot);
}

void release(Slot* slot) noexcept {
  if (slot == nullptr || g_board == nullptr) return;
  account_busy(*slot);
  slot->state.store(static_cast<std::uint32_t>(SlotState::kGone), std::memory_order_release);
  if (t_slot == slot) t_slot = nullptr;
  announce_change();
}

Seen look_before_check(Slot& slot) noexcept {
  // The full fence orders this thread's last store of its state (running)
  // before the loads: a conductor that reads the state after its change
  // bumped the epoch either sees this slot running (and raises its wake
  // word) or this thread reads the new epoch. The wake word first: when the
  // epoch read is the old one, the conductor's raise comes later and the
  // futex wait below returns at once.
  std::atomic_thread_fence(std::memory_order_seq_cst);
  const std::uint32_t wake = slot.wake.load(std::memory_order_seq_cst);
  return Seen{wake, g_board->epoch.load(std::memory_order_seq_cst)};
}

Wait wait_for_change(Slot& slot, const char* what, Seen seen, std::int64_t wake_at_ns,
                     std::uint32_t waits_for) noexcept {
  account_busy(slot);
  copy_text(slot.what, sizeof slot.what, what);
  slot.wake_at_ns.store(wake_at_ns, std::memory_order_relaxed);
  slot.waits_for.store(waits_for, std::memory_order_relaxed);
  slot.seen_epoch.store(seen.epoch, std::memory_order_relaxed);
  slot.blocks.fetch_add(1, std::memory_order_relaxed);
  slot.state.store(static_cast<std::uint32_t>(SlotState::kBlocked), std::memory_order_release);
  announce_change();
  const timespec a_second{1, 0};  // then see whether canhil is still there
  const long r = futex(&slot.wake, FUTEX_WAIT, seen.wake, &a_second);
  const int error = r == 0 ? 0 : errno;
  mark_running(slot);
  if (released()) {
    // The run is over: a wait with a virtual deadline ends as if it had come
    // (it never will); one without goes on as the real call.
    detach();
    return wake_at_ns == kNoWake ? Wait::kDetached : Wait::kTimedOut;
  }
  if (error == EINTR) return Wait::kInterrupted;
  if (error == ETIMEDOUT && conductor_gone()) {
    detach();
    return Wait::kDetached;
  }
  return Wait::kReady;
}

void post_change(std::uint32_t what) noexcept {
  // canhil's own process (the shim preloaded into it) makes its changes itself.
  if (board() == nullptr || g_conducting) return;
  g_board->posted.fetch_or(what, std::memory_order_release);
  announce_change();
}

void begin_signal_wait(const char* what) noexcept {
  Slot* slot = my_slot();
  if (slot == nullptr) return;
  account_busy(*slot);
  copy_text(slot->what, sizeof slot->what, what);
  slot->wake_at_ns.store(kNoWake, std::memory_order_relaxed);
  slot->signal_wait.store(1, std::memory_order_relaxed);
  slot->blocks.fetch_add(1, std::memory_order_relaxed);
  slot->state.store(static_cast<std::uint32_t>(SlotState::kBlocked), std::memory_order_release);
  announce_change();
}

void remember_started(pthread_t thread, Slot* slot) noexcept {
  const SpinLocked locked(g_started_lock);
  Started* entry = nullptr;
  for (Started& s : g_started) {
    if (s.slot != nullptr && pthread_equal(s.thread, thread) != 0) {
      entry = &s;  // a handle glibc reuses
      break;
    }
    if (s.slot == nullptr && entry == nullptr) entry = &s;
  }
  if (entry != nullptr) *entry = Started{thread, slot};
}

std::int32_t take_started(pthread_t thread) noexcept {
  Slot* slot = nullptr;
  {
    const SpinLocked locked(g_started_lock);
    for (Started& s : g_started) {
      if (s.slot != nullptr && pthread_equal(s.thread, thread) != 0) {
        slot = s.slot;
        s = Started{};
      }
    }
  }
  if (slot == nullptr) return 0;
  // The thread sets its id as its first act; it was created, so that is soon.
  const std::int64_t until = wall_ns() + kSecond;
  std::int32_t tid = 0;
  while ((tid = slot->tid.load(std::memory_order_acquire)) == 0 && wall_ns() < until) sched_yield();
  return tid;
}

void begin_join_wait(std::int32_t tid) noexcept {
  Slot* slot = my_slot();
  if (slot == nullptr) return;
  slot->join_tid.store(tid, std::memory_order_relaxed);
  begin_signal_wait("pthread_join");
}

void end_signal_wait() noexcept {
  Slot* slot = my_slot();
  if (slot == nullptr) return;
  slot->signal_wait.store(0, std::memory_order_relaxed);
  slot->join_tid.store(0, std::memory_order_relaxed);
  mark_running(*slot);
}

bool is_timer(int fd) noexcept {
  const SpinLocked locked(g_timers_lock);
  return find_timer(fd) != nullptr;
}

int new_timer(clockid_t clock, int flags) noexcept {
  const int fd = eventfd(0, flags & (TFD_NONBLOCK | TFD_CLOEXEC));
  if (fd < 0) return -1;
  const SpinLocked locked(g_timers_lock);
  Timer* t = find_timer(-1);
  if (t == nullptr) {
    close(fd);
    preload::say(kWho, "more than %zu timerfds: refused", g_timers.size());
    errno = EMFILE;
    return -1;
  }
  *t = Timer{fd, clock, kNoWake, 0};
  return fd;
}

int set_timer(int fd, int flags, const itimerspec* value, itimerspec* old) noexcept {
  const SpinLocked locked(g_timers_lock);
  Timer* t = find_timer(fd);
  if (t == nullptr || value == nullptr) {
    errno = t == nullptr ? EINVAL : EFAULT;
    return -1;
  }
  const std::int64_t now = now_ns();
  if (old != nullptr) {
    old->it_interval = timespec_of(t->interval_ns);
    old->it_value = timespec_of(t->next_ns == kNoWake ? 0 : t->next_ns - now);
  }
  const std::int64_t first = ns_of(value->it_value);
  t->interval_ns = ns_of(value->it_interval);
  if (first == 0) {
    t->next_ns = kNoWake;
  } else {
    t->next_ns = (flags & TFD_TIMER_ABSTIME) != 0 ? to_virtual(t->clock, first) : now + first;
  }
  drain(fd);  // arming resets the count of expirations, as timerfd_settime does
  return 0;
}

int get_timer(int fd, itimerspec* value) noexcept {
  const SpinLocked locked(g_timers_lock);
  const Timer* t = find_timer(fd);
  if (t == nullptr) {
    errno = EINVAL;
    return -1;
  }
  value->it_interval = timespec_of(t->interval_ns);
  value->it_value = timespec_of(t->next_ns == kNoWake ? 0 : t->next_ns - now_ns());
  return 0;
}

void forget_timer(int fd) noexcept {
  const SpinLocked locked(g_timers_lock);
  if (Timer* t = find_timer(fd)) *t = Timer{};
}

void fire_timers() noexcept {
  static const auto real_write = next_symbol<ssize_t (*)(int, const void*, size_t)>("write");
  const std::int64_t now = now_ns();
  const SpinLocked locked(g_timers_lock);
  for (Timer& t : g_timers) {
    if (t.fd < 0 || t.next_ns > now) continue;
    std::uint64_t expirations = 1;
    if (t.interval_ns > 0) {
      expirations += static_cast<std::uint64_t>((now - t.next_ns) / t.interval_ns);
      t.next_ns += static_cast<std::int64_t>(expirations) * t.interval_ns;
    } else {
      t.next_ns = kNoWake;
    }
    [[maybe_unused]] const auto r = real_write(t.fd, &expirations, sizeof expirations);
  }
}

std::int64_t next_timer() noexcept {
  const SpinLocked locked(g_timers_lock);
  std::int64_t next = kNoWake;
  for (const Timer& t : g_timers) {
    if (t.fd >= 0 && t.next_ns < next) next = t.next_ns;
  }
  return next;
}

}  // namespace canhil::lockstep::shim

// The hooks another preload calls (canhil/lockstep/shim_hook.h).

extern "C" __attribute__((visibility("default"))) void canhil_shim_frames_sent(long long frames) {
  using namespace canhil::lockstep::shim;
  if (frames <= 0 || board() == nullptr) return;
  if (canhil::lockstep::Slot* slot = my_slot())
    slot->frames_sent.fetch_add(static_cast<std::uint64_t>(frames), std::memory_order_release);
}

extern "C" __attribute__((visibility("default"))) long long canhil_shim_board_now(void) {
  using namespace canhil::lockstep::shim;
  return board() != nullptr ? static_cast<long long>(now_ns()) : -1;
}

extern "C" __attribute__((visibility("default"))) void canhil_shim_descriptor_readable(int /*fd*/) {
  // The conductor's next change wakes every thread waiting on descriptors.
  canhil::lockstep::shim::post_change(canhil::lockstep::kDescriptors);
}

/// Called by canhil's Conductor, through dlsym, when the shim is preloaded into
/// canhil itself: from then on this process's clocks read `board` (a team's
/// library that canhil loads stamps what it writes in virtual time, as the
/// team's processes do), while its waits stay real (canhil has no slot).
/// nullptr ends it. Returns 0.
extern "C" __attribute__((visibility("default"))) int canhil_timeshim_conduct(void* board) {
  using namespace canhil::lockstep::shim;
  if (board == nullptr) {
    g_conducting = false;
    g_board = nullptr;
    return 0;
  }
  g_board = static_cast<canhil::lockstep::Board*>(board);
  g_detached = false;  // a new run (the last one's board was released)
  g_conducting = true;
  return 0;
}
