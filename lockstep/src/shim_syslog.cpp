// A team's syslog in lockstep: what a process of the team logs through
// syslog(3) goes to its own standard error, the log canhil gives it (`--logs
// DIR`, else canhil's stderr), one line a message as glibc's LOG_PERROR
// writes it ("ident[pid]: message"), instead of the machine's syslog. On a
// machine without a syslog daemon (most containers and CI runners) glibc
// would try /dev/log at every message and, with LOG_CONS, write to the
// console: a slow device shared by every process, and messages nobody reads.
// With CANHIL_SYSLOG=system (`[external] syslog = "system"`), in real time
// (no lockstep) and in canhil's own process, messages go on to libc
// unchanged; openlog, closelog and setlogmask always do too.
#include <errno.h>
#include <sys/syscall.h>
#include <syslog.h>
#include <unistd.h>

#include <atomic>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "shim_core.hpp"

namespace {

namespace shim = canhil::lockstep::shim;

// openlog's ident and options, setlogmask's mask: as glibc keeps them, per process.
std::atomic_flag g_lock = ATOMIC_FLAG_INIT;
const char* g_ident = nullptr;  // openlog's pointer, kept as glibc keeps it (the caller's string)
int g_options = 0;
int g_mask = 0xff;

// Whether syslog goes to the process's stderr: in a team's process in
// lockstep (not canhil's own, where the shim conducts), unless CANHIL_SYSLOG
// says "system". Read once.
bool to_stderr() noexcept {
  static const bool system = [] {
    const char* v = std::getenv("CANHIL_SYSLOG");
    return v != nullptr && std::strcmp(v, "system") == 0;
  }();
  return !system && shim::active() && !shim::conducting();
}

// One message, formatted with the caller's errno (`saved`) for %m, on stderr
// in one write(2) past every preload's write().
void to_log(int priority, const char* format, va_list arguments, int saved) noexcept {
  const char* ident = nullptr;
  int options = 0;
  {
    const shim::SpinLocked held(g_lock);
    if ((LOG_MASK(LOG_PRI(priority)) & g_mask) == 0) return;
    ident = g_ident;
    options = g_options;
  }
  if (ident == nullptr) ident = program_invocation_short_name;
  char line[2048];
  int at = (options & LOG_PID) != 0 ? std::snprintf(line, sizeof line, "%s[%d]: ", ident, static_cast<int>(getpid()))
                                    : std::snprintf(line, sizeof line, "%s: ", ident);
  if (at < 0) at = 0;
  if (static_cast<std::size_t>(at) >= sizeof line - 2) at = static_cast<int>(sizeof line) - 2;
  errno = saved;  // %m is the caller's error
  const int n = std::vsnprintf(line + at, sizeof line - 1 - static_cast<std::size_t>(at), format, arguments);
  std::size_t size = static_cast<std::size_t>(at) + (n > 0 ? static_cast<std::size_t>(n) : 0);
  if (size > sizeof line - 2) size = sizeof line - 2;  // cut: a message is one line
  if (size == 0 || line[size - 1] != '\n') line[size++] = '\n';
  syscall(SYS_write, STDERR_FILENO, line, size);
  errno = saved;
}

// A message of vsyslog or __vsyslog_chk: written here when it goes to the
// process's stderr (true); else false, errno as the caller left it, for libc.
bool logged_here(int priority, const char* format, va_list arguments) noexcept {
  const int saved = errno;  // before anything the shim does may change it
  if (to_stderr()) {
    to_log(priority, format, arguments, saved);
    return true;
  }
  errno = saved;
  return false;
}

}  // namespace

#pragma GCC visibility push(default)
extern "C" {

// openlog, closelog and setlogmask are kept here and passed on to libc too,
// so that a process the run lets go on in real time logs as it asked.
void openlog(const char* ident, int options, int facility) {
  CANHIL_REAL(openlog);
  {
    const shim::SpinLocked held(g_lock);
    if (ident != nullptr) g_ident = ident;  // glibc keeps the ident it had
    g_options = options;
  }
  real_openlog(ident, options, facility);
}

void closelog() {
  CANHIL_REAL(closelog);
  {
    const shim::SpinLocked held(g_lock);
    g_ident = nullptr;
    g_options = 0;
  }
  real_closelog();
}

int setlogmask(int mask) {
  CANHIL_REAL(setlogmask);
  {
    const shim::SpinLocked held(g_lock);
    if (mask != 0) g_mask = mask;
  }
  return real_setlogmask(mask);
}

void vsyslog(int priority, const char* format, va_list arguments) {
  if (logged_here(priority, format, arguments)) return;
  CANHIL_REAL(vsyslog);
  real_vsyslog(priority, format, arguments);
}

void syslog(int priority, const char* format, ...) {
  va_list arguments;
  va_start(arguments, format);
  vsyslog(priority, format, arguments);
  va_end(arguments);
}

// glibc's fortified forms (_FORTIFY_SOURCE), which a program built so calls instead.
// NOLINTNEXTLINE(bugprone-reserved-identifier)
void __vsyslog_chk(int priority, int flag, const char* format, va_list arguments) {
  if (logged_here(priority, format, arguments)) return;
  using Real = void (*)(int, int, const char*, va_list);
  static const auto real = canhil::preload::next_symbol<Real>("__vsyslog_chk");
  real(priority, flag, format, arguments);
}

// NOLINTNEXTLINE(bugprone-reserved-identifier)
void __syslog_chk(int priority, int flag, const char* format, ...) {
  va_list arguments;
  va_start(arguments, format);
  __vsyslog_chk(priority, flag, format, arguments);
  va_end(arguments);
}

}  // extern "C"
#pragma GCC visibility pop
