// canhil/base/preload.hpp — the plumbing of a library preloaded (LD_PRELOAD)
// into programs canhil did not build, whatever calls it takes over: the next
// definition of a call it intercepts, a lookup of what another loaded library
// exports, a spin lock for its small tables, and a line on stderr. The time
// shim (lockstep/) stands on it, and so can a second preload beside it.
//
// Header-only and libc only: nothing of canhil's, no exceptions, no heap, no
// pthread mutex (a preloaded library runs before libc has finished starting
// and inside whatever state the program is in). dlsym is libc's own from
// glibc 2.34; with an older one link ${CMAKE_DL_LIBS}.
#pragma once

#include <dlfcn.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <ctime>

namespace canhil::preload {

/// The next definition of `name` after the calling library's, in the
/// dynamic linker's search order: libc's own call when no later preload takes
/// it over, else that preload's. nullptr if there is none. RTLD_NEXT is
/// relative to the object the code is compiled into, so each preload finds
/// what comes after itself. Look each call up once (a function-local static).
template <class F>
F next_symbol(const char* name) noexcept {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

/// In an intercepting call `fn`, declares `real_fn`: the next definition of
/// `fn` (libc's), looked up once, with `fn`'s own type:
///     ssize_t write(int fd, const void* b, size_t n) { CANHIL_REAL(write); ... real_write(fd, b, n) ... }
#define CANHIL_REAL(fn) static const auto real_##fn = ::canhil::preload::next_symbol<decltype(&::fn)>(#fn)

/// The same for a call of a given symbol version (`version` as "GLIBC_2.3.2"):
/// for calls libc keeps in several versions, where RTLD_NEXT alone may find
/// an old one (pthread_cond_wait).
template <class F>
F next_symbol(const char* name, const char* version) noexcept {
  return reinterpret_cast<F>(dlvsym(RTLD_NEXT, name, version));
}

/// libc's own definition of `name`, past every preload whatever the caller
/// is compiled into (a program that has a preload in front of its own calls:
/// canhil with the time shim in it, for the wall clock it must still read).
/// nullptr when libc does not define it. Look each call up once.
template <class F>
F libc_symbol(const char* name) noexcept {
  void* libc = dlopen("libc.so.6", RTLD_NOW | RTLD_NOLOAD);
  return libc != nullptr ? reinterpret_cast<F>(dlsym(libc, name)) : nullptr;
}

/// CLOCK_MONOTONIC as the machine has it, past a preload that makes the
/// clocks virtual (the time shim in canhil, or in whoever forked a bus's
/// broker): libc's own clock_gettime (the vDSO's, no system call), else the
/// system call.
inline timespec real_monotonic() noexcept {
  static const auto libc_clock = libc_symbol<int (*)(clockid_t, timespec*)>("clock_gettime");
  timespec ts{};
  if (libc_clock != nullptr) {
    libc_clock(CLOCK_MONOTONIC, &ts);
  } else {
    syscall(SYS_clock_gettime, CLOCK_MONOTONIC, &ts);
  }
  return ts;
}

/// real_monotonic() in nanoseconds.
inline std::int64_t real_monotonic_ns() noexcept {
  const timespec t = real_monotonic();
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

/// The first definition of `name` in the process, in whichever loaded object:
/// how one preload finds what another exports (a hook) without linking it.
/// nullptr when no loaded object defines it (that preload is not there).
template <class F>
F any_symbol(const char* name) noexcept {
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

/// Holds a spin lock for its scope (a preload's small tables; no pthread
/// mutex, which a preloaded library may meet before libc is ready). Hold it
/// for a few instructions only, and never across a call that may block.
class SpinLocked {
 public:
  explicit SpinLocked(std::atomic_flag& flag) noexcept : flag_(flag) {
    while (flag_.test_and_set(std::memory_order_acquire)) {
    }
  }
  ~SpinLocked() { flag_.clear(std::memory_order_release); }
  SpinLocked(const SpinLocked&) = delete;
  SpinLocked& operator=(const SpinLocked&) = delete;

 private:
  std::atomic_flag& flag_;
};

/// Writes "<who>[<pid>]: <message>\n" to stderr, the message formatted as
/// printf does (and cut at 511 characters). The line is formatted on the
/// stack and written with one write(2) system call, past every preload's
/// write() and without a stdio stream or its lock: it may be called before
/// libc's stdio is ready, after fork, or in a signal handler (vsnprintf, not
/// on POSIX's async-signal-safe list, takes no lock in glibc and allocates
/// nothing for %d, %u, %zu and %s). Lines of several processes do not mix.
/// errno is kept.
[[gnu::format(printf, 2, 3)]] inline void say(const char* who, const char* format, ...) noexcept {
  const int saved = errno;
  char message[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(message, sizeof message, format, args);
  va_end(args);
  char line[sizeof message + 96];
  const int n = std::snprintf(line, sizeof line, "%s[%d]: %s\n", who, static_cast<int>(getpid()), message);
  std::size_t left =
      n < 0 ? 0 : (static_cast<std::size_t>(n) < sizeof line ? static_cast<std::size_t>(n) : sizeof line - 1);
  const char* at = line;
  while (left > 0) {
    const long w = syscall(SYS_write, STDERR_FILENO, at, left);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) break;
    at += w;
    left -= static_cast<std::size_t>(w);
  }
  errno = saved;
}

}  // namespace canhil::preload
