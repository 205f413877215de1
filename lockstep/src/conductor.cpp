// canhil/lockstep/conductor.cpp — the board's owner (conductor.hpp).
#include "canhil/lockstep/conductor.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <linux/futex.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <new>
#include <optional>
#include <string>

#include "canhil/base/preload.hpp"
#include "canhil/base/process.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/base/start_again.hpp"
#include "canhil/lockstep/shim_hook.h"

namespace canhil::lockstep {
namespace {

std::atomic<int> g_boards{0};

Nanos wall_now() noexcept { return wall_clock(); }

SlotState state_of(const Slot& s) { return static_cast<SlotState>(s.state.load(std::memory_order_acquire)); }

std::string text_of(const char* chars, std::size_t size) { return std::string(chars, strnlen(chars, size)); }

std::string seconds(Nanos t) {
  char out[32];
  std::snprintf(out, sizeof out, "%.3f s", std::chrono::duration<double>(t).count());
  return out;
}

// A /proc stat line from the command's closing parenthesis on ("pid (comm)
// S ...": ") S ...", the command's name may hold spaces and parentheses);
// nullopt when the file cannot be read (the process or thread is gone).
std::optional<std::string> stat_fields(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (f == nullptr) return std::nullopt;
  char line[1024] = {};
  const bool read = std::fgets(line, sizeof line, f) != nullptr;
  std::fclose(f);
  const char* end_of_name = read ? std::strrchr(line, ')') : nullptr;
  return std::string(end_of_name != nullptr ? end_of_name : "");
}

// Whether a thread exists and has not ended: a process that exited stays a
// zombie until its parent reaps it, and a zombie runs no more.
bool running_thread(int pid, int tid) {
  if (syscall(SYS_tgkill, pid, tid, 0) != 0 && errno == ESRCH) return false;
  const char state = thread_state(pid, tid);
  return state != '?' && state != 'Z' && state != 'X';
}

// Whether the slot's thread is runnable (state R: on a CPU, or waiting for
// one on a busy machine), not blocked.
bool runnable(const Slot& s) {
  const int pid = s.pid.load();
  const int tid = s.tid.load();
  return pid > 0 && tid > 0 && thread_state(pid, tid) == 'R';
}

bool alive(const Slot& s) {
  const int pid = s.pid.load();
  const int tid = s.tid.load();
  if (tid == 0) return kill(pid, 0) == 0 || errno != ESRCH;  // a thread not yet started
  return running_thread(pid, tid);
}

// The boards of canhil processes that ended without removing theirs (killed
// outright: SIGKILL, an out-of-memory kill), this user's, from /dev/shm
// (`canhil-lockstep-<pid>-<n>`); a board of a process that still runs stays.
void remove_orphan_boards() {
  for_each_left_by_the_dead("/dev/shm", "canhil-lockstep-", '-', [](const std::filesystem::path& board) {
    shm_unlink(("/" + board.filename().string()).c_str());
  });
}

}  // namespace

Nanos wall_clock() noexcept {
  // In a run whose canhil is itself preloaded with the shim (a team library
  // stamping items), the clock_gettime the program calls is virtual.
  const timespec ts = ::canhil::preload::real_monotonic();
  return std::chrono::seconds(ts.tv_sec) + Nanos(ts.tv_nsec);
}

Conductor::Conductor(ConductorOptions options) : options_(options) {
  remove_orphan_boards();
  name_ = "/canhil-lockstep-" + std::to_string(getpid()) + "-" + std::to_string(g_boards.fetch_add(1));
  const int fd = shm_open(name_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw SetupError("canhil: cannot create the lockstep board " + name_ + " (" + std::strerror(errno) +
                     "): is /dev/shm mounted and writable?");
  }
  const bool sized = ftruncate(fd, sizeof(Board)) == 0;
  void* mapped = sized ? mmap(nullptr, sizeof(Board), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0) : MAP_FAILED;
  close(fd);
  if (mapped == MAP_FAILED) {
    const std::string why = std::strerror(errno);
    shm_unlink(name_.c_str());
    throw SetupError("canhil: cannot map the lockstep board " + name_ + " (" + why + ")");
  }
  board_ = new (mapped) Board();
  board_->conductor_pid = getpid();
  board_->realtime_base_ns = options_.realtime_base_ns;
  board_->monotonic_base_ns = options_.monotonic_base_ns;
  board_->version = kVersion;
  std::atomic_thread_fence(std::memory_order_release);
  board_->magic = kMagic;
  // The shim preloaded into canhil itself: this process's clocks follow the board too.
  if (const auto conduct = preload::any_symbol<canhil_timeshim_conduct_fn>(CANHIL_TIMESHIM_CONDUCT)) {
    conduct(board_);
    clocks_here_ = true;
  }
}

Conductor::~Conductor() {
  if (board_ == nullptr) return;
  release();
  if (clocks_here_) {
    preload::any_symbol<canhil_timeshim_conduct_fn>(CANHIL_TIMESHIM_CONDUCT)(nullptr);
  }
  // Anyone still waiting learns at its next check that canhil is gone.
  munmap(board_, sizeof(Board));
  shm_unlink(name_.c_str());
}

std::vector<std::string> Conductor::environment(const std::filesystem::path& shim, const char* preload_already) const {
  return {std::string(kBoardVariable) + "=" + name_,
          "LD_PRELOAD=" + preload_list(shim.string(), preload_already != nullptr ? preload_already : "")};
}

std::size_t Conductor::wait_attached(std::size_t count, Nanos limit) {
  const Nanos until = wall_now() + limit;
  for (;;) {
    // Processes, not threads: a handler with two threads is one of `count`.
    std::vector<std::int32_t> pids;
    for (const Slot& s : board_->slots) {
      const std::int32_t pid = s.pid.load(std::memory_order_acquire);
      if (state_of(s) != SlotState::kFree && std::find(pids.begin(), pids.end(), pid) == pids.end())
        pids.push_back(pid);
    }
    const std::size_t attached = pids.size();
    if (attached >= count || wall_now() > until) return attached;
    const std::uint32_t seen = board_->changes.load(std::memory_order_acquire);
    const timespec a_while{0, 20'000'000};
    futex(&board_->changes, FUTEX_WAIT, seen, &a_while);
  }
}

void Conductor::set_time(Nanos now) {
  const std::int64_t ns = now.count();
  if (ns <= board_->now_ns.load(std::memory_order_relaxed)) return;
  board_->now_ns.store(ns, std::memory_order_release);
  if (next_wakeup() <= now) change(kTimeOnly, false);  // only those whose time has come
}

Nanos Conductor::now() const noexcept { return Nanos(board_->now_ns.load(std::memory_order_acquire)); }

void Conductor::nudge(std::uint32_t what) { change(what, false); }

void Conductor::change(std::uint32_t what, bool everyone) {
  // The epoch first, as a full barrier: a thread about to block either read
  // this epoch (and checks after the change) or is seen below as running and
  // has its wake word raised (its wait then returns at once).
  const std::uint32_t epoch = board_->epoch.fetch_add(1, std::memory_order_seq_cst) + 1;
  for (std::size_t kind = 0; kind < kChangeKinds; ++kind) {
    if ((what & (1U << kind)) != 0) changed_at_[kind] = epoch;
  }
  const std::int64_t now = board_->now_ns.load(std::memory_order_relaxed);
  for (Slot& s : board_->slots) {
    const SlotState state = static_cast<SlotState>(s.state.load(std::memory_order_seq_cst));
    if (state == SlotState::kFree || state == SlotState::kGone) continue;
    const bool blocked = state == SlotState::kBlocked;
    // A signal wait is not on its word; a wait this change does not concern
    // stays quiet at its epoch (quiet_pass).
    if (blocked && !everyone &&
        (s.signal_wait.load(std::memory_order_relaxed) != 0 ||
         (s.waits_for.load(std::memory_order_relaxed) & what) == 0) &&
        s.wake_at_ns.load(std::memory_order_relaxed) > now) {
      continue;
    }
    s.wake.fetch_add(1, std::memory_order_seq_cst);
    if (blocked) futex(&s.wake, FUTEX_WAKE, INT_MAX, nullptr);
  }
}

bool Conductor::untouched_since(const Slot& s, std::uint32_t seen) const noexcept {
  if (s.wake_at_ns.load(std::memory_order_relaxed) <= board_->now_ns.load(std::memory_order_relaxed)) return false;
  const std::uint32_t waits = s.waits_for.load(std::memory_order_relaxed);
  for (std::size_t kind = 0; kind < kChangeKinds; ++kind) {
    // Epochs wrap: compare by difference.
    if ((waits & (1U << kind)) != 0 && static_cast<std::int32_t>(seen - changed_at_[kind]) < 0) return false;
  }
  return true;
}

std::uint32_t Conductor::epoch() const noexcept { return board_->epoch.load(std::memory_order_acquire); }

void Conductor::release() {
  if (board_->released.exchange(1, std::memory_order_acq_rel) == 0) change(kEveryChange, true);
}

bool Conductor::released() const noexcept { return board_->released.load(std::memory_order_acquire) != 0; }

Nanos Conductor::next_wakeup() const noexcept {
  std::int64_t next = kNoWake;
  for (const Slot& s : board_->slots) {
    if (state_of(s) == SlotState::kBlocked && s.signal_wait.load(std::memory_order_relaxed) == 0) {
      next = std::min(next, s.wake_at_ns.load(std::memory_order_relaxed));
    }
  }
  return Nanos(next);
}

bool Conductor::quiet(std::string* who) {
  // A thread that ends wakes the threads joining it: once one has been
  // retired in a pass, a joiner counted quiet earlier in that pass may be
  // running now, so the pass is made again.
  bool retired = true;
  while (retired) {
    retired = false;
    if (!quiet_pass(who, retired)) return false;
  }
  return true;
}

bool Conductor::quiet_pass(std::string* who, bool& retired) {
  const std::uint32_t epoch = board_->epoch.load(std::memory_order_acquire);
  for (Slot& s : board_->slots) {
    const SlotState state = state_of(s);
    if (state == SlotState::kFree) continue;
    if (state == SlotState::kGone) {
      // A thread that said goodbye is quiet once it has really ended: until
      // then a thread joining it has not been woken.
      if (!alive(s)) {
        retire(s);
        retired = true;
        continue;
      }
    } else if (state == SlotState::kBlocked) {
      const int joined = s.join_tid.load(std::memory_order_relaxed);
      if (s.signal_wait.load(std::memory_order_relaxed) != 0) {
        if (joined == 0 || running_thread(s.pid.load(), joined)) continue;
      } else {
        const std::uint32_t seen = s.seen_epoch.load(std::memory_order_relaxed);
        if (seen == epoch || untouched_since(s, seen)) continue;
      }
    }
    if (who != nullptr) {
      std::string doing = " did not come back from " + text_of(s.what, sizeof s.what);
      if (state == SlotState::kRunning) doing = " kept running and did not wait again";
      if (state == SlotState::kGone) doing = " is ending and has not ended";
      *who = text_of(s.name, sizeof s.name) + " (pid " + std::to_string(s.pid.load()) + ", thread " +
             std::to_string(s.tid.load()) + ")" + doing;
    }
    return false;
  }
  return true;
}

void Conductor::retire(Slot& s) {
  // Keep its figures for the summary, then free the slot.
  const int pid = s.pid.load();
  auto it = std::find_if(freed_.begin(), freed_.end(), [pid](const ProcessReport& r) { return r.pid == pid; });
  if (it == freed_.end()) it = freed_.insert(freed_.end(), ProcessReport{text_of(s.name, sizeof s.name), pid});
  it->threads += 1;
  it->blocks += s.blocks.load();
  it->frames_sent += s.frames_sent.load();
  it->busy_wall += Nanos(s.busy_wall_ns.load());
  frames_of_freed_ += s.frames_sent.load();
  s.state.store(static_cast<std::uint32_t>(SlotState::kFree), std::memory_order_release);
  s.pid.store(0, std::memory_order_release);
}

void Conductor::sweep_dead() {
  for (Slot& s : board_->slots) {
    const SlotState state = state_of(s);
    if (state == SlotState::kFree) continue;
    if (!alive(s)) retire(s);
  }
}

std::string Conductor::wait_quiet(const std::function<std::string()>& also, const std::string& waiting_for,
                                  std::optional<Nanos> limit, int ready_fd, const std::function<bool()>& arrived) {
  const Nanos answer_limit = limit.value_or(options_.answer_limit);
  const Nanos start = wall_now();
  Nanos until = start + answer_limit;
  // Past the limit the processes' CPU time says whether they are computing
  // (wait on, up to the busy limit) or stuck (named now).
  const Nanos busy_until = start + std::max(answer_limit, options_.busy_limit);
  // Read only once a wait outlasts the limit (never on the instants that
  // answer in time): a first sample, then a short window to judge by.
  std::optional<Nanos> cpu_then;
  Nanos cpu_seen_at = start;
  bool computing = false;
  // A process that died without a word (killed, or a shell that exited
  // without the shim's goodbye) is looked for every 50 ms of a long wait: it
  // may die at any time during it, not only at its start.
  constexpr Nanos kSweepEvery = std::chrono::milliseconds(50);
  Nanos next_sweep = start + kSweepEvery;
  for (;;) {
    const std::uint32_t seen = board_->changes.load(std::memory_order_acquire);
    // What a process changed for another (a sem_post) becomes a change now;
    // one posted after this look keeps them from counting as quiet below.
    if (const std::uint32_t posted = board_->posted.exchange(0, std::memory_order_acq_rel)) nudge(posted);
    std::string who;
    const bool processes_quiet = quiet(&who) && board_->posted.load(std::memory_order_acquire) == 0;
    const std::string missing = processes_quiet && also ? also() : std::string();
    if (processes_quiet && missing.empty()) break;
    const Nanos now = wall_now();
    if (now >= next_sweep) {
      sweep_dead();
      next_sweep = now + kSweepEvery;
      continue;
    }
    if (now > until) {
      const Nanos window = std::min(answer_limit, Nanos(std::chrono::milliseconds(200)));
      if (!cpu_then) {
        cpu_then = processes_cpu();
        cpu_seen_at = now;
        until = now + window;
        continue;
      }
      const Nanos cpu_now = processes_cpu();
      // On the CPU a tenth of the window, or runnable now: a busy machine
      // (a build beside the run) may give a computing process less.
      computing = (cpu_now - *cpu_then) * 10 >= now - cpu_seen_at || any_runnable();
      if (computing && now < busy_until) {
        cpu_then = cpu_now;
        cpu_seen_at = now;
        until = std::min(busy_until, now + window);
        continue;
      }
      waited_ += now - start;
      const std::string within = seconds(computing ? busy_until - start : answer_limit) + " of wall time";
      const std::string state = computing ? " (still computing on the CPU: hung in a loop? busy_limit_s in [external] "
                                            "or [teams.external] waits longer)"
                                          : " (not on the CPU: blocked on something canhil will not give)";
      if (!processes_quiet) return who + " within " + within + " after " + waiting_for + state;
      return "canhil waited " + within + " after " + waiting_for + " for " + missing + state;
    }
    const int fd_to_watch = processes_quiet ? ready_fd : -1;
    if (look_briefly(seen, fd_to_watch, arrived)) {
      ++looks_answered_;
      continue;
    }
    ++sleeps_;
    // canhil's own condition may change without a board change; what only
    // `arrived` tells (the user-space bus's rounds) has no descriptor to wake
    // the sleep, so it is asked again sooner.
    const timespec a_while{0, arrived && fd_to_watch >= 0 ? 50'000 : 1'000'000};
    if (fd_to_watch >= 0) {
      // Only canhil's own condition is missing: it changes when a frame
      // arrives on canhil's sockets. The system call itself, not poll(): a
      // time shim preloaded into canhil would wait in virtual time.
      pollfd p{fd_to_watch, POLLIN, 0};
      syscall(SYS_ppoll, &p, 1, &a_while, nullptr, 8);
    } else {
      futex(&board_->changes, FUTEX_WAIT, seen, &a_while);
    }
  }
  waited_ += wall_now() - start;
  return {};
}

bool Conductor::look_briefly(std::uint32_t seen, int ready_fd, const std::function<bool()>& arrived) const {
  if (options_.spin <= Nanos{0}) return ready_fd >= 0 && arrived && arrived();  // one look, in memory
  const Nanos until = wall_now() + options_.spin;
  const timespec at_once{0, 0};
  pollfd p{ready_fd, POLLIN, 0};
  for (;;) {
    if (board_->changes.load(std::memory_order_acquire) != seen) return true;
    if (board_->posted.load(std::memory_order_acquire) != 0) return true;  // a sem_post to pass on
    if (ready_fd >= 0) {
      if (arrived) {
        if (arrived()) return true;
      } else if (syscall(SYS_ppoll, &p, 1, &at_once, nullptr, 8) > 0) {  // the system call itself, as below
        return true;
      }
    }
    if (wall_now() >= until) return false;
    sched_yield();
  }
}

std::optional<Nanos> cpu_time_of(int pid) {
  const auto fields = stat_fields("/proc/" + std::to_string(pid) + "/stat");
  if (!fields || fields->empty()) return std::nullopt;
  // After the parenthesis come field 3 (the state) and on; utime and stime
  // are fields 14 and 15: the 12th and 13th words there.
  const char* p = fields->c_str();
  for (int word = 0; p != nullptr && word < 12; ++word) p = std::strchr(p + 1, ' ');
  if (p == nullptr) return std::nullopt;
  char* end = nullptr;
  const unsigned long long user = std::strtoull(p + 1, &end, 10);
  const unsigned long long system = end != nullptr ? std::strtoull(end, nullptr, 10) : 0;
  static const long kTicks = sysconf(_SC_CLK_TCK);
  return Nanos(kTicks > 0 ? static_cast<long long>(user + system) * (1'000'000'000LL / kTicks) : 0);
}

bool Conductor::any_runnable() const {
  return std::any_of(std::begin(board_->slots), std::end(board_->slots),
                     [](const Slot& s) { return state_of(s) != SlotState::kFree && runnable(s); });
}

Nanos Conductor::processes_cpu() const {
  std::vector<int> pids;
  for (const Slot& s : board_->slots) {
    if (state_of(s) == SlotState::kFree) continue;
    const int pid = s.pid.load(std::memory_order_relaxed);
    if (pid > 0 && std::find(pids.begin(), pids.end(), pid) == pids.end()) pids.push_back(pid);
  }
  Nanos sum{0};
  for (const int pid : pids) sum += cpu_time_of(pid).value_or(Nanos{0});
  return sum;
}

std::uint64_t Conductor::frames_sent() const noexcept {
  std::uint64_t sum = frames_of_freed_;
  for (const Slot& s : board_->slots) {
    if (state_of(s) != SlotState::kFree) sum += s.frames_sent.load(std::memory_order_acquire);
  }
  return sum;
}

std::vector<ProcessReport> Conductor::processes() const {
  std::vector<ProcessReport> out = freed_;
  for (ProcessReport& r : out) r.gone = true;
  for (const Slot& s : board_->slots) {
    if (state_of(s) == SlotState::kFree) continue;
    const int pid = s.pid.load();
    auto it = std::find_if(out.begin(), out.end(), [pid](const ProcessReport& r) { return r.pid == pid; });
    if (it == out.end()) it = out.insert(out.end(), ProcessReport{text_of(s.name, sizeof s.name), pid});
    it->gone = state_of(s) == SlotState::kGone;
    it->threads += 1;
    it->blocks += s.blocks.load();
    it->frames_sent += s.frames_sent.load();
    it->busy_wall += Nanos(s.busy_wall_ns.load());
  }
  return out;
}

}  // namespace canhil::lockstep
