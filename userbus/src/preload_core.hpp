// The preload's own state (libcanhil-bus.so): the bus's mapped state, which of
// the process's descriptors are bus sockets, and the few things every
// intercepted call needs. Private to the preload.
#pragma once

#include <sys/socket.h>
#include <sys/types.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>

#include "canhil/userbus/state.hpp"

namespace canhil::userbus::preload {

/// RAW_MIN_NAMELEN: a CAN address's family and interface index, what
/// getsockname and recvfrom give.
inline constexpr socklen_t kMinName = 8;

/// The bus's state, mapped (again when the bus was started anew), or nullptr
/// when no bus runs. Cheap after the first call; `refresh` looks at the file
/// again (socket() and the name lookups do).
State* bus_state(bool refresh) noexcept;

/// The bus socket behind descriptor `fd`, or nullptr when `fd` is not one.
/// `stale` is set when it was one of a bus that has since stopped.
Socket* socket_of(int fd, bool* stale = nullptr) noexcept;

/// Records `fd` as the bus socket in `slot` of the current bus; -1 forgets it.
void mark(int fd, int slot) noexcept;
/// `to` is the same socket as `from` (dup, dup2, dup3, fcntl F_DUPFD).
void copy_mark(int from, int to) noexcept;

/// A new bus socket: a connection to the broker, its slot marked. `extra`:
/// SOCK_NONBLOCK and SOCK_CLOEXEC as socket() was given them. The
/// descriptor, or -1 with errno; -2 when no bus runs (the kernel decides).
int open_socket(int extra) noexcept;

/// Tells the broker that interfaces changed (one went down or up).
void interfaces_changed() noexcept;
/// One request to the broker on a control connection of its own; its answer (0 or -errno).
int ask_broker(const ControlRequest& request) noexcept;

/// Copies `n` bytes from the program's `from` to `to`, or false when `from`
/// is not readable memory (the kernel's EFAULT), without a fault.
bool copy_in(void* to, const void* from, std::size_t n) noexcept;
/// Copies `n` bytes to the program's `to`, or false when it is not writable.
bool copy_out(void* to, const void* from, std::size_t n) noexcept;

/// The interface of index `index` or called `name` on the current bus.
Interface* interface_at(int index) noexcept;
Interface* interface_named(const char* name) noexcept;

/// errno set to `e`, and -1: a call's failure as libc reports it.
inline int fail(int e) noexcept {
  errno = e;
  return -1;
}

/// The interface ioctls (SIOCGIFINDEX, SIOCGIFNAME, SIOCGIFFLAGS,
/// SIOCSIFFLAGS, SIOCGIFMTU, SIOCSIFMTU) for the bus's interfaces, on any
/// descriptor; 1 when `request` is not one of them or the interface is not
/// the bus's (the kernel answers).
int interface_ioctl(unsigned long request, void* arg) noexcept;

/// The lockstep time shim's hooks, when it is loaded beside this preload.
void count_sent(long long frames) noexcept;
/// The run's virtual time, or -1 (no shim, or not in a lockstep run).
long long board_now() noexcept;

}  // namespace canhil::userbus::preload
