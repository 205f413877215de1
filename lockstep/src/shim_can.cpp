// The kernel's CAN sockets, the first user of the shim's hooks
// (canhil/lockstep/shim_hook.h): a frame written to an AF_CAN socket is
// counted as sent (in flight until canhil sees it on the bus). The rest of
// the shim knows nothing of CAN.
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdint>

#include "canhil/lockstep/shim_hook.h"
#include "shim_core.hpp"

namespace {

namespace shim = canhil::lockstep::shim;

/// Counts `frames` written to `fd` if it is one of the kernel's CAN sockets.
/// The kernel is asked directly (not through getsockopt(), which another
/// preload may answer for descriptors of its own, counted through the hook
/// by that preload).
void count_if_can(int fd, std::int64_t frames) noexcept {
  // canhil's own process counts its frames itself (it has no slot to count them in).
  if (frames <= 0 || !shim::active() || shim::conducting()) return;
  int domain = 0;
  socklen_t size = sizeof domain;
  if (syscall(SYS_getsockopt, fd, SOL_SOCKET, SO_DOMAIN, &domain, &size) != 0 || domain != AF_CAN) return;
  canhil_shim_frames_sent(frames);
}

}  // namespace

#pragma GCC visibility push(default)
extern "C" {

ssize_t write(int fd, const void* buffer, size_t size) {
  CANHIL_REAL(write);
  const ssize_t r = real_write(fd, buffer, size);
  if (r > 0) count_if_can(fd, 1);
  return r;
}

ssize_t send(int fd, const void* buffer, size_t size, int flags) {
  CANHIL_REAL(send);
  const ssize_t r = real_send(fd, buffer, size, flags);
  if (r > 0) count_if_can(fd, 1);
  return r;
}

ssize_t sendto(int fd, const void* buffer, size_t size, int flags, const sockaddr* to, socklen_t to_size) {
  CANHIL_REAL(sendto);
  const ssize_t r = real_sendto(fd, buffer, size, flags, to, to_size);
  if (r > 0) count_if_can(fd, 1);
  return r;
}

ssize_t sendmsg(int fd, const msghdr* message, int flags) {
  CANHIL_REAL(sendmsg);
  const ssize_t r = real_sendmsg(fd, message, flags);
  if (r > 0) count_if_can(fd, 1);
  return r;
}

int sendmmsg(int fd, mmsghdr* messages, unsigned int count, int flags) {
  CANHIL_REAL(sendmmsg);
  const int r = real_sendmmsg(fd, messages, count, flags);
  if (r > 0) count_if_can(fd, r);
  return r;
}

}  // extern "C"
#pragma GCC visibility pop
