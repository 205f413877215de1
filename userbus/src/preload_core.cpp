// The preload's state: the mapped bus, the descriptors that are bus sockets,
// opening a socket, and finding the bus sockets a program was started with
// (exec keeps descriptors, not a process's memory).
#include "preload_core.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "canhil/base/preload.hpp"
#include "canhil/lockstep/shim_hook.h"

namespace canhil::userbus::preload {
namespace {

constexpr int kMaxFd = 1 << 16;
constexpr std::uint32_t kSlotBits = 11;  // kMaxSockets + 1 values

// Each descriptor: 0 when not a bus socket, else the bus generation (the
// high bits) and its slot + 1.
std::atomic<std::uint32_t> g_fds[kMaxFd];
std::atomic<State*> g_state{nullptr};
std::atomic<std::uint32_t> g_generation{0};
std::atomic_flag g_map_lock = ATOMIC_FLAG_INIT;
ino_t g_inode = 0;
dev_t g_device = 0;

struct Paths {
  char folder[256];
  char socket[sizeof(sockaddr_un{}.sun_path)];
  char state[300];
  bool ok;
};

Paths paths() noexcept {
  Paths p{};
  p.ok = bus_folder(p.folder, sizeof p.folder) && bus_path(p.socket, sizeof p.socket, p.folder, "bus.sock") &&
         bus_path(p.state, sizeof p.state, p.folder, "state");
  return p;
}

State* map_state(const Paths& p) noexcept {
  const int fd = static_cast<int>(syscall(SYS_openat, AT_FDCWD, p.state, O_RDWR | O_CLOEXEC));
  if (fd < 0) return nullptr;
  struct stat st {};
  State* result = nullptr;
  if (fstat(fd, &st) == 0 && static_cast<std::size_t>(st.st_size) >= sizeof(State)) {
    {
      ::canhil::preload::SpinLocked locked(g_map_lock);
      State* current = g_state.load(std::memory_order_acquire);
      if (current != nullptr && st.st_ino == g_inode && st.st_dev == g_device) {
        result = current;
      } else {
        void* m = mmap(nullptr, sizeof(State), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        if (m != MAP_FAILED) {
          auto* s = static_cast<State*>(m);
          if (s->magic == kMagic && s->version == kVersion) {
            // An earlier bus's mapping stays (another thread may still read it).
            g_inode = st.st_ino;
            g_device = st.st_dev;
            g_generation.fetch_add(1, std::memory_order_acq_rel);
            g_state.store(s, std::memory_order_release);
            result = s;
          } else {
            munmap(m, sizeof(State));
          }
        }
      }
    }
  }
  syscall(SYS_close, fd);
  return result;
}

/// Whether `fd` is a connection to the bus at `p`: its slot, else -1.
int slot_behind(int fd, const Paths& p, State& s) noexcept {
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISSOCK(st.st_mode)) return -1;
  sockaddr_un peer{};
  socklen_t len = sizeof peer;
  if (syscall(SYS_getpeername, fd, &peer, &len) != 0 || peer.sun_family != AF_UNIX ||
      std::strncmp(peer.sun_path, p.socket, sizeof peer.sun_path) != 0) {
    return -1;
  }
  sockaddr_un self{};
  len = sizeof self;
  if (syscall(SYS_getsockname, fd, &self, &len) != 0 || len <= sizeof(sa_family_t)) return -1;
  const std::size_t n = len - sizeof(sa_family_t);
  for (int k = 0; k < kMaxSockets; ++k) {
    const Socket& sk = s.sockets[k];
    if (sk.in_use.load(std::memory_order_acquire) != 0 &&
        std::memcmp(sk.peer, self.sun_path, n < sizeof sk.peer ? n : sizeof sk.peer) == 0) {
      return k;
    }
  }
  return -1;
}

/// At start-up: the bus sockets this program was given (exec keeps them open).
[[gnu::constructor]] void find_inherited() {
  const Paths p = paths();
  if (!p.ok || access(p.state, F_OK) != 0) return;
  State* s = map_state(p);
  if (s == nullptr) return;
  const int dir = static_cast<int>(syscall(SYS_openat, AT_FDCWD, "/proc/self/fd", O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (dir < 0) return;
  char buffer[4096];
  for (;;) {
    const long n = syscall(SYS_getdents64, dir, buffer, sizeof buffer);
    if (n <= 0) break;
    for (long at = 0; at < n;) {
      auto* d = reinterpret_cast<dirent64*>(buffer + at);
      at += d->d_reclen;
      char* end = nullptr;
      const long fd = std::strtol(d->d_name, &end, 10);
      if (end == d->d_name || *end != '\0' || fd == dir || fd >= kMaxFd) continue;
      const int slot = slot_behind(static_cast<int>(fd), p, *s);
      if (slot >= 0) mark(static_cast<int>(fd), slot);
    }
  }
  syscall(SYS_close, dir);
}

}  // namespace

State* bus_state(bool refresh) noexcept {
  State* s = g_state.load(std::memory_order_acquire);
  if (s != nullptr && !refresh) return s;
  const Paths p = paths();
  if (!p.ok) return nullptr;
  s = map_state(p);
  if (s == nullptr) return nullptr;
  // A state file left by a broker that died is no bus.
  if (s->broker_pid <= 0 || (kill(s->broker_pid, 0) != 0 && errno == ESRCH)) return nullptr;
  return s;
}

Socket* socket_of(int fd, bool* stale) noexcept {
  if (fd < 0 || fd >= kMaxFd) return nullptr;
  const std::uint32_t v = g_fds[fd].load(std::memory_order_acquire);
  if (v == 0) return nullptr;
  State* s = g_state.load(std::memory_order_acquire);
  const std::uint32_t generation = v >> kSlotBits;
  if (s == nullptr || generation != (g_generation.load(std::memory_order_acquire) & ((1U << (32 - kSlotBits)) - 1))) {
    if (stale != nullptr) *stale = true;
    return nullptr;
  }
  return &s->sockets[(v & ((1U << kSlotBits) - 1)) - 1];
}

void mark(int fd, int slot) noexcept {
  if (fd < 0 || fd >= kMaxFd) return;
  const std::uint32_t generation = g_generation.load(std::memory_order_acquire) & ((1U << (32 - kSlotBits)) - 1);
  g_fds[fd].store(slot < 0 ? 0 : (generation << kSlotBits) | static_cast<std::uint32_t>(slot + 1),
                  std::memory_order_release);
}

void copy_mark(int from, int to) noexcept {
  if (to < 0 || to >= kMaxFd) return;
  const std::uint32_t v = (from >= 0 && from < kMaxFd) ? g_fds[from].load(std::memory_order_acquire) : 0;
  g_fds[to].store(v, std::memory_order_release);
}

int open_socket(int extra) noexcept {
  State* s = bus_state(true);
  if (s == nullptr) return -2;
  const Paths p = paths();
  CANHIL_REAL(socket);
  CANHIL_REAL(bind);
  CANHIL_REAL(connect);
  CANHIL_REAL(close);
  CANHIL_REAL(send);
  CANHIL_REAL(recv);
  const int fd = real_socket(AF_UNIX, SOCK_SEQPACKET | (extra & SOCK_CLOEXEC), 0);
  if (fd < 0) return -1;
  if (fd >= kMaxFd) {
    real_close(fd);
    errno = EMFILE;
    return -1;
  }
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  // An autobound name ("\0" and five hex digits): how a program started with
  // this descriptor finds its slot again.
  if (real_bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(sa_family_t)) != 0) {
    real_close(fd);
    return -1;
  }
  std::memcpy(a.sun_path, p.socket, sizeof a.sun_path);
  const Hello h{kHelloSocket, static_cast<std::int32_t>(getpid())};
  Welcome w{-EIO};
  const bool connected = real_connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  if (!connected && (errno == ECONNREFUSED || errno == ENOENT)) {
    // Nobody listens: the broker died, perhaps a zombie nobody reaped (a
    // container whose first process reaps none), so its pid still answers
    // kill(). No bus runs: the kernel answers, as without one.
    real_close(fd);
    return -2;
  }
  if (!connected || real_send(fd, &h, sizeof h, MSG_NOSIGNAL) != static_cast<ssize_t>(sizeof h) ||
      real_recv(fd, &w, sizeof w, 0) != static_cast<ssize_t>(sizeof w) || w.slot < 0 || w.slot >= kMaxSockets) {
    const int e = w.slot < 0 && w.slot != -EIO ? -w.slot : ENOBUFS;
    real_close(fd);
    errno = e;
    return -1;
  }
  if ((extra & SOCK_NONBLOCK) != 0) {
    CANHIL_REAL(fcntl);
    real_fcntl(fd, F_SETFL, real_fcntl(fd, F_GETFL) | O_NONBLOCK);
  }
  mark(fd, w.slot);
  return fd;
}

void interfaces_changed() noexcept { ask_broker(ControlRequest{kControlInterfacesChanged}); }

int ask_broker(const ControlRequest& r) noexcept {
  const Paths p = paths();
  const int fd = static_cast<int>(syscall(SYS_socket, AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0));
  if (fd < 0) return -errno;
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::memcpy(a.sun_path, p.socket, sizeof a.sun_path);
  const Hello h{kHelloControl, static_cast<std::int32_t>(getpid())};
  int answer = -EIO;
  if (syscall(SYS_connect, fd, &a, sizeof a) == 0 &&
      syscall(SYS_sendto, fd, &h, sizeof h, MSG_NOSIGNAL, nullptr, 0) > 0 &&
      syscall(SYS_sendto, fd, &r, sizeof r, MSG_NOSIGNAL, nullptr, 0) > 0) {
    syscall(SYS_recvfrom, fd, &answer, sizeof answer, 0, nullptr, nullptr);
  }
  syscall(SYS_close, fd);
  return answer;
}

bool copy_in(void* to, const void* from, std::size_t n) noexcept {
  if (n == 0) return true;
  if (from == nullptr) return false;
  iovec local{to, n};
  iovec remote{const_cast<void*>(from), n};
  if (process_vm_readv(getpid(), &local, 1, &remote, 1, 0) == static_cast<ssize_t>(n)) return true;
  if (errno == EFAULT) return false;
  std::memcpy(to, from, n);  // the call is not allowed here (a seccomp profile): trust the pointer
  return true;
}

bool copy_out(void* to, const void* from, std::size_t n) noexcept {
  if (n == 0) return true;
  if (to == nullptr) return false;
  iovec local{const_cast<void*>(from), n};
  iovec remote{to, n};
  if (process_vm_writev(getpid(), &local, 1, &remote, 1, 0) == static_cast<ssize_t>(n)) return true;
  if (errno == EFAULT) return false;
  std::memcpy(to, from, n);
  return true;
}

Interface* interface_at(int index) noexcept {
  State* s = bus_state(false);
  return s == nullptr ? nullptr : find_interface(*s, index);
}

Interface* interface_named(const char* name) noexcept {
  State* s = bus_state(true);
  return s == nullptr ? nullptr : find_interface(*s, name);
}

long long board_now() noexcept {
  static const auto hook = ::canhil::preload::any_symbol<canhil_shim_board_now_fn>("canhil_shim_board_now");
  return hook != nullptr ? hook() : -1;
}

void count_sent(long long frames) noexcept {
  static const auto hook = ::canhil::preload::any_symbol<canhil_shim_frames_sent_fn>("canhil_shim_frames_sent");
  if (hook != nullptr) hook(frames);
}

}  // namespace canhil::userbus::preload
