// A program that plays a team's external process under the time shim: it
// reads the clocks, sleeps, polls, reads a timerfd, starts a thread, spins
// without ever waiting, waits on or posts a semaphore, logs through syslog,
// or plays a second preload through the shim's hooks,
// and prints what its clocks said at each point
// (lines "<what> <CLOCK_MONOTONIC in ns>"). tests/lockstep/conductor_test.cpp
// moves the virtual clock and checks the lines.
#include <fcntl.h>
#include <poll.h>
#include <semaphore.h>
#include <signal.h>
#include <sys/select.h>
#include <sys/syscall.h>
#include <sys/time.h>
#include <sys/timerfd.h>
#include <syslog.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "canhil/base/preload.hpp"
#include "canhil/lockstep/shim_hook.h"

// glibc's fortified syslog, which a program built with _FORTIFY_SOURCE calls
// instead of syslog(); declared here to call it without that.
// NOLINTNEXTLINE(bugprone-reserved-identifier)
extern "C" void __syslog_chk(int priority, int flag, const char* format, ...);

namespace {

long long mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1'000'000'000LL + ts.tv_nsec;
}

void say(const char* what) {
  std::printf("%s %lld\n", what, mono_ns());
  std::fflush(stdout);
}

int clocks() {
  timeval tv{};
  gettimeofday(&tv, nullptr);
  std::printf("realtime %lld.%06lld time %lld\n", static_cast<long long>(tv.tv_sec), static_cast<long long>(tv.tv_usec),
              static_cast<long long>(time(nullptr)));
  say("start");
  const timespec quarter{0, 250'000'000};
  nanosleep(&quarter, nullptr);
  say("nanosleep");
  usleep(100'000);
  say("usleep");
  sleep(1);
  say("sleep");
  timespec until{};
  clock_gettime(CLOCK_MONOTONIC, &until);
  until.tv_nsec += 50'000'000;
  if (until.tv_nsec >= 1'000'000'000) {
    until.tv_nsec -= 1'000'000'000;
    until.tv_sec += 1;
  }
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr);
  say("clock_nanosleep");
  timeval twenty_ms{0, 20'000};
  select(0, nullptr, nullptr, nullptr, &twenty_ms);
  say("select");
  return 0;
}

int wait_on_fifo(const char* path) {
  const int fd = open(path, O_RDONLY | O_NONBLOCK);
  if (fd < 0) return 2;
  pollfd p{fd, POLLIN, 0};
  const int first = poll(&p, 1, 500);
  say(first == 0 ? "poll-timeout" : "poll-early");
  p.revents = 0;
  const int second = poll(&p, 1, -1);
  char c = 0;
  const bool got = second == 1 && read(fd, &c, 1) == 1;
  say(got && c == 'x' ? "poll-readable" : "poll-wrong");
  return 0;
}

int ticks() {
  const int fd = timerfd_create(CLOCK_MONOTONIC, 0);
  itimerspec every{{0, 10'000'000}, {0, 10'000'000}};
  timerfd_settime(fd, 0, &every, nullptr);
  for (int i = 0; i < 5; ++i) {
    std::uint64_t count = 0;
    if (read(fd, &count, sizeof count) != sizeof count) return 2;
    say(count == 1 ? "tick" : "tick-several");
  }
  return 0;
}

int thread() {
  std::thread worker([] {
    const timespec a_while{0, 30'000'000};
    nanosleep(&a_while, nullptr);
    say("worker");
  });
  worker.join();
  say("joined");
  return 0;
}

// As a library that retries its wait after a signal until its deadline (the
// builtin RTDB's DB_wait_frame): an hour's sleep, resumed after each EINTR.
extern "C" void on_interrupt(int) {}

int patient() {
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigaction(SIGINT, &action, nullptr);
  say("patient");
  timespec left{3600, 0};
  while (nanosleep(&left, &left) != 0 && errno == EINTR) {
  }
  std::printf("patient woke\n");
  return 0;
}

int spin() {
  say("spinning");
  volatile unsigned long n = 0;
  for (;;) n = n + 1;
}

// CPU time by the system call itself (the shim gives clocks of virtual time).
double cpu_seconds() {
  timespec t{};
  syscall(SYS_clock_gettime, CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

// A slow first cycle (a team's agent building its maps): `ms` of CPU time
// without a call the shim sees, then a virtual sleep of 10 ms.
int compute(double ms) {
  say("computing");
  volatile unsigned long n = 0;
  while (cpu_seconds() < ms / 1000) n = n + 1;
  say("computed");
  const timespec ten_ms{0, 10'000'000};
  nanosleep(&ten_ms, nullptr);
  say("slept");
  return 0;
}

// Blocked where canhil cannot see or end it: 30 s of the real clock.
int blocked() {
  say("blocking");
  const timespec wall{30, 0};
  syscall(SYS_nanosleep, &wall, nullptr);
  return 0;
}

// What a second preload (a bus in user space) does, played by the program
// itself: it puts a byte in a pipe with the system call (the shim sees no
// write, and the kernel wakes nobody the shim could see: a virtual wait looks
// again only when told) and tells the shim through its hooks, found as that
// preload finds them, with two frames sent. A second thread waits for the
// pipe in a poll with no timeout.
int hook() {
  const auto readable =
      canhil::preload::any_symbol<canhil_shim_descriptor_readable_fn>("canhil_shim_descriptor_readable");
  const auto sent = canhil::preload::any_symbol<canhil_shim_frames_sent_fn>("canhil_shim_frames_sent");
  if (readable == nullptr || sent == nullptr) {
    say("no-hooks");
    return 2;
  }
  int fds[2];
  if (pipe(fds) != 0) return 2;
  std::thread reader([fd = fds[0]] {
    pollfd p{fd, POLLIN, 0};
    say(poll(&p, 1, -1) == 1 ? "readable" : "poll-wrong");
  });
  const timespec tenth{0, 100'000'000};
  nanosleep(&tenth, nullptr);
  // Woken at 100 ms, as the reader was: 20 ms of CPU first, so that the reader
  // has looked again and waits (without the hook, until the clock next moves).
  volatile unsigned long n = 0;
  while (cpu_seconds() < 0.020) n = n + 1;
  const char byte = 'x';
  if (syscall(SYS_write, fds[1], &byte, 1) != 1) return 2;
  sent(2);
  readable(fds[0]);
  say("written");
  const timespec half{0, 500'000'000};
  nanosleep(&half, nullptr);
  reader.join();
  say("joined");
  return 0;
}

// A wait for a signal with a timeout (SIGUSR1 blocked, never sent): it ends
// by the timeout, whether the shim plays a run's clock or not.
int signal_wait() {
  sigset_t usr1;
  sigemptyset(&usr1);
  sigaddset(&usr1, SIGUSR1);
  sigprocmask(SIG_BLOCK, &usr1, nullptr);
  const timespec tenth{0, 100'000'000};
  const int got = sigtimedwait(&usr1, nullptr, &tenth);
  say(got < 0 && errno == EAGAIN ? "sigtimedwait-timeout" : "sigtimedwait-wrong");
  return 0;
}

// A team's process between two looks: a sleep of a second.
int sleeper() {
  const timespec second{1, 0};
  nanosleep(&second, nullptr);
  say("slept");
  return 0;
}

// Two of a team's processes waking each other through a named semaphore:
// one waits for it, the other posts it after 300 ms.
int semaphore_wait(const char* name) {
  sem_t* s = sem_open(name, O_CREAT, 0600, 0);
  if (s == SEM_FAILED) return 2;
  say(sem_wait(s) == 0 ? "posted" : "sem-wrong");
  return 0;
}

int semaphore_post(const char* name) {
  sem_t* s = sem_open(name, O_CREAT, 0600, 0);
  if (s == SEM_FAILED) return 2;
  const timespec a_while{0, 300'000'000};
  nanosleep(&a_while, nullptr);
  say(sem_post(s) == 0 ? "post" : "post-wrong");
  return 0;
}

// A team's logging through syslog(3): plain, with %m, under a mask, the
// fortified form, after closelog; after a sleep, so that the messages are
// logged in lockstep, at a virtual instant. `perror`: LOG_PERROR too (glibc
// then also writes each message it gets on stderr).
int logs(bool perror) {
  const timespec a_while{0, 100'000'000};
  nanosleep(&a_while, nullptr);
  openlog("teamlog", LOG_PID | (perror ? LOG_PERROR : 0), LOG_USER);
  syslog(LOG_INFO, "cycle %d", 42);
  errno = ENOENT;
  syslog(LOG_WARNING, "no map: %m");
  setlogmask(LOG_UPTO(LOG_NOTICE));
  syslog(LOG_DEBUG, "hidden by the mask");
  __syslog_chk(LOG_ERR, 1, "fortified %s", "too");
  setlogmask(LOG_UPTO(LOG_DEBUG));
  closelog();
  syslog(LOG_NOTICE, "after closelog");
  say("logged");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "clocks") return clocks();
  if (mode == "fifo" && argc > 2) return wait_on_fifo(argv[2]);
  if (mode == "timerfd") return ticks();
  if (mode == "thread") return thread();
  if (mode == "spin") return spin();
  if (mode == "compute" && argc > 2) return compute(std::strtod(argv[2], nullptr));
  if (mode == "blocked") return blocked();
  if (mode == "patient") return patient();
  if (mode == "hook") return hook();
  if (mode == "sigtimedwait") return signal_wait();
  if (mode == "sleeper") return sleeper();
  if (mode == "sem-wait" && argc > 2) return semaphore_wait(argv[2]);
  if (mode == "sem-post" && argc > 2) return semaphore_post(argv[2]);
  if (mode == "syslog") return logs(argc > 2 && std::strcmp(argv[2], "perror") == 0);
  std::fprintf(stderr,
               "usage: lockstep_client clocks|fifo PATH|timerfd|thread|spin|compute MS|blocked|patient|hook|"
               "sigtimedwait|sleeper|sem-wait NAME|sem-post NAME|syslog [perror]\n");
  return 2;
}
