// The calls the time shim takes over (exported with C linkage, found before
// libc's by the dynamic linker when the shim is preloaded). Each one passes
// straight through when the process is not in a lockstep run.
//
// Clocks: the virtual ones read the board. Waiting calls become shim::block:
// a non-blocking check of the real call, then a wait for canhil's next change
// until the call's virtual timeout. (Writes to the kernel's CAN sockets are
// counted in shim_can.cpp.)
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <semaphore.h>
#include <signal.h>
#include <sys/epoll.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/timerfd.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "shim_core.hpp"

namespace shim = canhil::lockstep::shim;
using canhil::lockstep::kDescriptors;
using canhil::lockstep::kNoWake;
using canhil::lockstep::kOtherChanges;
using canhil::lockstep::kSemaphores;
using canhil::lockstep::kTimeOnly;
using shim::Wait;

namespace {

using shim::kSecond;
using shim::next_symbol;
using shim::ns_of;
using shim::timespec_of;

bool valid(const timespec& ts) noexcept { return ts.tv_sec >= 0 && ts.tv_nsec >= 0 && ts.tv_nsec < kSecond; }

std::int64_t after(std::int64_t delay_ns) noexcept {
  const std::int64_t now = shim::now_ns();
  return delay_ns >= kNoWake - now ? kNoWake : now + delay_ns;
}
std::int64_t after_ms(int timeout_ms) noexcept {
  return timeout_ms < 0 ? kNoWake : after(std::int64_t{timeout_ms} * 1'000'000);
}

/// Whether a read on `fd` would wait (a blocking descriptor).
bool blocking(int fd) noexcept {
  const int flags = fcntl(fd, F_GETFL);
  return flags >= 0 && (flags & O_NONBLOCK) == 0;
}

/// A socket's SO_RCVTIMEO as a virtual wake-up time (kNoWake without one).
std::int64_t receive_deadline(int fd) noexcept {
  timeval tv{};
  socklen_t size = sizeof tv;
  if (getsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, &size) != 0 || (tv.tv_sec == 0 && tv.tv_usec == 0)) return kNoWake;
  return after(tv.tv_sec * kSecond + tv.tv_usec * 1000);
}

bool readable_now(int fd) noexcept {
  CANHIL_REAL(poll);
  pollfd p{fd, POLLIN, 0};
  return real_poll(&p, 1, 0) != 0;
}

/// Blocks until `fd` is readable (or its receive timeout passes); false with
/// errno set when the caller must return -1 instead of reading.
bool wait_readable(const char* what, int fd, int flags) noexcept {
  if (!shim::active() || (flags & MSG_DONTWAIT) != 0 || !blocking(fd)) return true;
  switch (shim::block(what, receive_deadline(fd), kDescriptors, [fd] { return readable_now(fd); })) {
    case Wait::kTimedOut:
      errno = EAGAIN;
      return false;
    case Wait::kInterrupted:
      errno = EINTR;
      return false;
    default:
      return true;
  }
}

/// The kernel's receive time stamps (SO_TIMESTAMP, SO_TIMESTAMPNS, the
/// software one of SO_TIMESTAMPING) are wall time: they become the virtual
/// CLOCK_REALTIME of the read. In lockstep a frame is read in the instant it
/// was sent, unless the reader let it wait, and then the read's time is what
/// its clock says anyway: deterministic either way.
void virtual_stamps(msghdr& message) noexcept {
  std::int64_t now = 0;
  if (message.msg_control == nullptr || !shim::virtual_reading(CLOCK_REALTIME, now)) return;
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    unsigned char* data = CMSG_DATA(c);
    const std::size_t size = c->cmsg_len - CMSG_LEN(0);
    if (c->cmsg_type == SO_TIMESTAMP && size >= sizeof(timeval)) {
      const timeval tv{now / kSecond, (now % kSecond) / 1000};
      std::memcpy(data, &tv, sizeof tv);
    } else if (c->cmsg_type == SO_TIMESTAMPNS && size >= sizeof(timespec)) {
      const timespec ts = timespec_of(now);
      std::memcpy(data, &ts, sizeof ts);
    } else if (c->cmsg_type == SO_TIMESTAMPING && size >= 3 * sizeof(timespec)) {
      timespec stamps[3];
      std::memcpy(stamps, data, sizeof stamps);
      if (stamps[0].tv_sec != 0 || stamps[0].tv_nsec != 0) stamps[0] = timespec_of(now);  // the software one
      std::memcpy(data, stamps, sizeof stamps);
    }
  }
}

constexpr int kDoTheRealCall = -1;

/// Sleeps until virtual `wake_at`: 0; EINTR with the time left in `left`; or
/// kDoTheRealCall when canhil is gone.
int sleep_until(const char* what, std::int64_t wake_at, std::int64_t& left) noexcept {
  const Wait w = shim::block(what, wake_at, kTimeOnly, [] { return false; });
  left = 0;
  if (w == Wait::kDetached) return kDoTheRealCall;
  if (w == Wait::kInterrupted) {
    left = wake_at - shim::now_ns();
    return EINTR;
  }
  return 0;
}

/// Runs a blocking call's body with `mask` as the signal mask (ppoll, pselect).
class MaskFor {
 public:
  explicit MaskFor(const sigset_t* mask) noexcept : set_(mask != nullptr) {
    if (set_) pthread_sigmask(SIG_SETMASK, mask, &old_);
  }
  ~MaskFor() {
    if (set_) pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  MaskFor(const MaskFor&) = delete;
  MaskFor& operator=(const MaskFor&) = delete;

 private:
  bool set_;
  sigset_t old_{};
};

/// What ends a wait on `count` descriptors: their changes, or only the clock
/// when there are none (a poll or select used as a sleep).
template <class Count>
constexpr std::uint32_t waits_for_descriptors(Count count) noexcept {
  return count == 0 ? kTimeOnly : kDescriptors;
}

/// What a call built on block() returns: the ready result, 0 on timeout, -1 EINTR.
template <class Check>
int wait_result(const char* what, std::int64_t wake_at, std::uint32_t waits_for, int& result, Check check) noexcept {
  switch (shim::block(what, wake_at, waits_for, [&] {
    result = check();
    return result != 0;
  })) {
    case Wait::kReady:
      return result;
    case Wait::kTimedOut:
      return 0;
    case Wait::kInterrupted:
      errno = EINTR;
      return -1;
    case Wait::kDetached:
      break;
  }
  return -2;  // the caller does the real call
}

struct ThreadStart {
  void* (*start)(void*);
  void* argument;
  canhil::lockstep::Slot* slot;
};

void* start_thread(void* p) {
  const ThreadStart start = *static_cast<ThreadStart*>(p);
  std::free(p);
  shim::adopt(start.slot);
  return start.start(start.argument);
}

// Runs `call` (the real blocking call) with the slot marked as waiting for a
// signal or for another thread: quiet at any epoch.
template <class Call>
auto in_signal_wait(const char* what, Call call) noexcept {
  shim::begin_signal_wait(what);
  const auto r = call();
  shim::end_signal_wait();
  return r;
}

}  // namespace

// Only these calls are exported (the library is built with hidden visibility).
#pragma GCC visibility push(default)
extern "C" {

// Clocks.
int clock_gettime(clockid_t clock, timespec* ts) {
  CANHIL_REAL(clock_gettime);
  std::int64_t ns = 0;
  if (!shim::virtual_reading(clock, ns)) return real_clock_gettime(clock, ts);
  *ts = timespec_of(ns);
  return 0;
}

int gettimeofday(timeval* tv, void* tz) {
  CANHIL_REAL(gettimeofday);
  std::int64_t ns = 0;
  if (!shim::virtual_reading(CLOCK_REALTIME, ns)) return real_gettimeofday(tv, tz);
  tv->tv_sec = ns / kSecond;
  tv->tv_usec = (ns % kSecond) / 1000;
  return 0;
}

time_t time(time_t* out) {
  CANHIL_REAL(time);
  std::int64_t ns = 0;
  if (!shim::virtual_reading(CLOCK_REALTIME, ns)) return real_time(out);
  const time_t seconds = ns / kSecond;
  if (out != nullptr) *out = seconds;
  return seconds;
}

// Sleeps.
int clock_nanosleep(clockid_t clock, int flags, const timespec* request, timespec* remain) {
  CANHIL_REAL(clock_nanosleep);
  std::int64_t ignored = 0;
  if (request == nullptr || !shim::virtual_reading(clock, ignored)) {
    return real_clock_nanosleep(clock, flags, request, remain);
  }
  if (!valid(*request)) return EINVAL;
  const bool absolute = (flags & TIMER_ABSTIME) != 0;
  const std::int64_t wake_at = absolute ? shim::to_virtual(clock, ns_of(*request)) : after(ns_of(*request));
  std::int64_t left = 0;
  const int r = sleep_until("clock_nanosleep", wake_at, left);
  if (r == kDoTheRealCall) return real_clock_nanosleep(clock, flags, request, remain);
  if (r == EINTR && remain != nullptr && !absolute) *remain = timespec_of(left);
  return r;
}

int nanosleep(const timespec* request, timespec* remain) {
  CANHIL_REAL(nanosleep);
  if (request == nullptr || !shim::active()) return real_nanosleep(request, remain);
  if (!valid(*request)) {
    errno = EINVAL;
    return -1;
  }
  std::int64_t left = 0;
  const int r = sleep_until("nanosleep", after(ns_of(*request)), left);
  if (r == 0) return 0;
  if (r == kDoTheRealCall) return real_nanosleep(request, remain);
  if (remain != nullptr) *remain = timespec_of(left);
  errno = EINTR;
  return -1;
}

int usleep(useconds_t microseconds) {
  CANHIL_REAL(usleep);
  if (!shim::active()) return real_usleep(microseconds);
  std::int64_t left = 0;
  const int r = sleep_until("usleep", after(std::int64_t{microseconds} * 1000), left);
  if (r == 0) return 0;
  if (r == kDoTheRealCall) return real_usleep(microseconds);
  errno = EINTR;
  return -1;
}

unsigned int sleep(unsigned int seconds) {
  CANHIL_REAL(sleep);
  if (!shim::active()) return real_sleep(seconds);
  std::int64_t left = 0;
  if (sleep_until("sleep", after(std::int64_t{seconds} * kSecond), left) == kDoTheRealCall) return real_sleep(seconds);
  return static_cast<unsigned int>((left + kSecond - 1) / kSecond);
}

// Waiting for descriptors.
int poll(pollfd* fds, nfds_t count, int timeout_ms) {
  CANHIL_REAL(poll);
  if (!shim::active() || timeout_ms == 0) return real_poll(fds, count, timeout_ms);
  int result = 0;
  const int r = wait_result("poll", after_ms(timeout_ms), waits_for_descriptors(count), result,
                            [&] { return real_poll(fds, count, 0); });
  if (r != -2) {
    if (r == 0) {
      for (nfds_t i = 0; i < count; ++i) fds[i].revents = 0;
    }
    return r;
  }
  return real_poll(fds, count, timeout_ms);
}

int ppoll(pollfd* fds, nfds_t count, const timespec* timeout, const sigset_t* mask) {
  CANHIL_REAL(ppoll);
  if (!shim::active() || (timeout != nullptr && ns_of(*timeout) == 0)) return real_ppoll(fds, count, timeout, mask);
  const timespec zero{0, 0};
  int result = 0;
  const MaskFor masked(mask);
  const int r =
      wait_result("ppoll", timeout == nullptr ? kNoWake : after(ns_of(*timeout)), waits_for_descriptors(count), result,
                  [&] { return real_ppoll(fds, count, &zero, nullptr); });
  if (r != -2) {
    if (r == 0) {
      for (nfds_t i = 0; i < count; ++i) fds[i].revents = 0;
    }
    return r;
  }
  return real_ppoll(fds, count, timeout, nullptr);
}

int select(int count, fd_set* reads, fd_set* writes, fd_set* errors, timeval* timeout) {
  CANHIL_REAL(select);
  if (!shim::active() || (timeout != nullptr && timeout->tv_sec == 0 && timeout->tv_usec == 0)) {
    return real_select(count, reads, writes, errors, timeout);
  }
  fd_set r0{}, w0{}, e0{};
  if (reads != nullptr) r0 = *reads;
  if (writes != nullptr) w0 = *writes;
  if (errors != nullptr) e0 = *errors;
  const auto restore = [&] {
    if (reads != nullptr) *reads = r0;
    if (writes != nullptr) *writes = w0;
    if (errors != nullptr) *errors = e0;
  };
  const std::int64_t wake_at =
      timeout == nullptr ? kNoWake : after(timeout->tv_sec * kSecond + timeout->tv_usec * 1000);
  int result = 0;
  const int r = wait_result("select", wake_at, waits_for_descriptors(count), result, [&] {
    restore();
    timeval zero{0, 0};
    return real_select(count, reads, writes, errors, &zero);
  });
  if (r == -2) {
    restore();
    return real_select(count, reads, writes, errors, timeout);
  }
  if (r == 0) {
    if (reads != nullptr) FD_ZERO(reads);
    if (writes != nullptr) FD_ZERO(writes);
    if (errors != nullptr) FD_ZERO(errors);
    if (timeout != nullptr) *timeout = timeval{0, 0};
  }
  return r;
}

int pselect(int count, fd_set* reads, fd_set* writes, fd_set* errors, const timespec* timeout, const sigset_t* mask) {
  CANHIL_REAL(pselect);
  if (!shim::active()) return real_pselect(count, reads, writes, errors, timeout, mask);
  const MaskFor masked(mask);
  timeval tv{};
  if (timeout != nullptr) tv = timeval{timeout->tv_sec, timeout->tv_nsec / 1000};
  return select(count, reads, writes, errors, timeout == nullptr ? nullptr : &tv);
}

int epoll_wait(int epoll, epoll_event* events, int most, int timeout_ms) {
  CANHIL_REAL(epoll_wait);
  if (!shim::active() || timeout_ms == 0) return real_epoll_wait(epoll, events, most, timeout_ms);
  int result = 0;
  const int r = wait_result("epoll_wait", after_ms(timeout_ms), kDescriptors, result,
                            [&] { return real_epoll_wait(epoll, events, most, 0); });
  return r != -2 ? r : real_epoll_wait(epoll, events, most, timeout_ms);
}

int epoll_pwait(int epoll, epoll_event* events, int most, int timeout_ms, const sigset_t* mask) {
  CANHIL_REAL(epoll_pwait);
  if (!shim::active() || timeout_ms == 0) return real_epoll_pwait(epoll, events, most, timeout_ms, mask);
  const MaskFor masked(mask);
  return epoll_wait(epoll, events, most, timeout_ms);
}

// Reading: a blocking read waits in virtual time until the descriptor is readable.
ssize_t read(int fd, void* buffer, size_t size) {
  CANHIL_REAL(read);
  // (an emulated timerfd becomes readable when the wait fires it)
  if (!wait_readable("read", fd, 0)) return -1;
  return real_read(fd, buffer, size);
}

ssize_t recv(int fd, void* buffer, size_t size, int flags) {
  CANHIL_REAL(recv);
  if (!wait_readable("recv", fd, flags)) return -1;
  return real_recv(fd, buffer, size, flags);
}

ssize_t recvfrom(int fd, void* buffer, size_t size, int flags, sockaddr* from, socklen_t* from_size) {
  CANHIL_REAL(recvfrom);
  if (!wait_readable("recvfrom", fd, flags)) return -1;
  return real_recvfrom(fd, buffer, size, flags, from, from_size);
}

ssize_t recvmsg(int fd, msghdr* message, int flags) {
  CANHIL_REAL(recvmsg);
  if (!wait_readable("recvmsg", fd, flags)) return -1;
  const ssize_t r = real_recvmsg(fd, message, flags);
  if (r >= 0) virtual_stamps(*message);
  return r;
}

// Timers: a timerfd on a virtual clock becomes an eventfd the shim fills.
int timerfd_create(clockid_t clock, int flags) {
  CANHIL_REAL(timerfd_create);
  std::int64_t ignored = 0;
  if (!shim::virtual_reading(clock, ignored) || shim::conducting()) return real_timerfd_create(clock, flags);
  return shim::new_timer(clock, flags);
}

int timerfd_settime(int fd, int flags, const itimerspec* value, itimerspec* old) {
  CANHIL_REAL(timerfd_settime);
  if (!shim::active() || !shim::is_timer(fd)) return real_timerfd_settime(fd, flags, value, old);
  return shim::set_timer(fd, flags, value, old);
}

int timerfd_gettime(int fd, itimerspec* value) {
  CANHIL_REAL(timerfd_gettime);
  if (!shim::active() || !shim::is_timer(fd)) return real_timerfd_gettime(fd, value);
  return shim::get_timer(fd, value);
}

int close(int fd) {
  CANHIL_REAL(close);
  if (shim::active()) shim::forget_timer(fd);
  return real_close(fd);
}

// Waiting for a signal: quiet at any epoch (what ends it is canhil's business: PMan's SIGCONT).
int sigsuspend(const sigset_t* mask) {
  CANHIL_REAL(sigsuspend);
  return in_signal_wait("sigsuspend", [&] { return real_sigsuspend(mask); });
}

int pause() {
  CANHIL_REAL(pause);
  return in_signal_wait("pause", [&] { return real_pause(); });
}

int sigwaitinfo(const sigset_t* set, siginfo_t* info) {
  CANHIL_REAL(sigwaitinfo);
  return in_signal_wait("sigwaitinfo", [&] { return real_sigwaitinfo(set, info); });
}

int sigwait(const sigset_t* set, int* signal) {
  CANHIL_REAL(sigwait);
  return in_signal_wait("sigwait", [&] { return real_sigwait(set, signal); });
}

int sigtimedwait(const sigset_t* set, siginfo_t* info, const timespec* timeout) {
  CANHIL_REAL(sigtimedwait);
  if (timeout == nullptr) return sigwaitinfo(set, info);
  if (!shim::active()) return real_sigtimedwait(set, info, timeout);
  // The signals waited for are blocked, so they stay pending: check, then wait for canhil's next change.
  const timespec zero{0, 0};
  int result = 0;
  const int r = wait_result("sigtimedwait", after(ns_of(*timeout)), kOtherChanges, result, [&] {
    const int s = real_sigtimedwait(set, info, &zero);
    return s >= 0 ? s : (errno == EAGAIN ? 0 : -1);
  });
  if (r == -2) return real_sigtimedwait(set, info, timeout);
  if (r == 0) {
    errno = EAGAIN;
    return -1;
  }
  return r;
}

pid_t waitpid(pid_t pid, int* status, int options) {
  CANHIL_REAL(waitpid);
  if ((options & WNOHANG) != 0) return real_waitpid(pid, status, options);
  return in_signal_wait("waitpid", [&] { return real_waitpid(pid, status, options); });
}

pid_t wait(int* status) { return waitpid(-1, status, 0); }

// Waiting for another thread: quiet at any epoch, since that thread has a
// slot of its own that keeps the clock while it runs.
int pthread_join(pthread_t thread, void** result) {
  CANHIL_REAL(pthread_join);
  const std::int32_t tid = shim::take_started(thread);
  if (tid != 0) {
    shim::begin_join_wait(tid);
  } else {
    shim::begin_signal_wait("pthread_join");
  }
  const int r = real_pthread_join(thread, result);
  shim::end_signal_wait();
  return r;
}

int pthread_cond_wait(pthread_cond_t* condition, pthread_mutex_t* mutex) {
  static const auto real_wait =
      next_symbol<int (*)(pthread_cond_t*, pthread_mutex_t*)>("pthread_cond_wait", "GLIBC_2.3.2");
  return in_signal_wait("pthread_cond_wait", [&] { return real_wait(condition, mutex); });
}

// Semaphores (a process-shared one is how canhil's RTDB wakes its agent): a
// try, then a wait for canhil's next change, until the virtual deadline.
int sem_wait(sem_t* semaphore) {
  CANHIL_REAL(sem_wait);
  CANHIL_REAL(sem_trywait);
  if (!shim::active()) return real_sem_wait(semaphore);
  int result = 0;
  const int r =
      wait_result("sem_wait", kNoWake, kSemaphores, result, [&] { return real_sem_trywait(semaphore) == 0 ? 1 : 0; });
  if (r == -2) return real_sem_wait(semaphore);
  return r == 1 ? 0 : -1;  // -1: EINTR
}

int sem_timedwait(sem_t* semaphore, const timespec* deadline) {
  CANHIL_REAL(sem_timedwait);
  CANHIL_REAL(sem_trywait);
  if (!shim::active()) return real_sem_timedwait(semaphore, deadline);
  if (!valid(*deadline)) {
    errno = EINVAL;
    return -1;
  }
  int result = 0;
  const int r = wait_result("sem_timedwait", shim::to_virtual(CLOCK_REALTIME, ns_of(*deadline)), kSemaphores, result,
                            [&] { return real_sem_trywait(semaphore) == 0 ? 1 : 0; });
  if (r == -2) return real_sem_timedwait(semaphore, deadline);
  if (r == 0) {
    errno = ETIMEDOUT;
    return -1;
  }
  return r == 1 ? 0 : -1;  // -1: EINTR
}

// A post another thread or process may wait for: the conductor's next change
// wakes the threads waiting on semaphores (it would not for CAN frames alone).
int sem_post(sem_t* semaphore) {
  CANHIL_REAL(sem_post);
  const int r = real_sem_post(semaphore);
  if (r == 0) shim::post_change(kSemaphores);
  return r;
}

// Threads: the clock waits for a new thread from its first instruction.
int pthread_create(pthread_t* thread, const pthread_attr_t* attributes, void* (*start)(void*), void* argument) {
  CANHIL_REAL(pthread_create);
  canhil::lockstep::Slot* slot = shim::claim_for_new_thread();
  if (slot == nullptr) return real_pthread_create(thread, attributes, start, argument);
  auto* wrapped = static_cast<ThreadStart*>(std::malloc(sizeof(ThreadStart)));
  if (wrapped == nullptr) {
    shim::release(slot);
    return EAGAIN;
  }
  *wrapped = ThreadStart{start, argument, slot};
  const int r = real_pthread_create(thread, attributes, start_thread, wrapped);
  if (r != 0) {
    std::free(wrapped);
    shim::release(slot);
  } else {
    shim::remember_started(*thread, slot);
  }
  return r;
}

}  // extern "C"
#pragma GCC visibility pop
