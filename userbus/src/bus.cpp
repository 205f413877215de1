// The bus's folder, files and interfaces from canhil's side (bus.hpp).
#include "canhil/userbus/bus.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "broker_system.hpp"
#include "bus_internal.hpp"
#include "canhil/base/assets.hpp"
#include "canhil/base/errno_text.hpp"
#include "canhil/base/realtime.hpp"
#include "canhil/base/start_again.hpp"
#include "canhil/userbus/bus_hook.h"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {
namespace {

int connect_to(const BusPaths& paths) {
  const int fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", paths.socket.c_str());
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

int ask_broker(const BusPaths& paths, const ControlRequest& r) {
  const int fd = connect_to(paths);
  if (fd < 0) return -errno;
  const Hello h{kHelloControl, getpid()};
  int answer = -EIO;
  if (send(fd, &h, sizeof h, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof h) &&
      send(fd, &r, sizeof r, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof r)) {
    if (recv(fd, &answer, sizeof answer, 0) != static_cast<ssize_t>(sizeof answer)) answer = -EIO;
  }
  close(fd);
  return answer;
}

int ask_broker(const BusPaths& paths, std::uint32_t op) { return ask_broker(paths, ControlRequest{op}); }

namespace {

// When the bus at `paths` was started by a canhil whose state has another
// layout (State::version): what to tell the user; else empty.
std::string of_another_canhil(const BusPaths& paths) {
  std::uint32_t head[2] = {0, 0};  // State's magic and version
  const int fd = ::open(paths.state.c_str(), O_RDONLY | O_CLOEXEC);
  const bool read_head = fd >= 0 && ::read(fd, head, sizeof head) == static_cast<ssize_t>(sizeof head);
  if (fd >= 0) close(fd);
  if (!read_head || head[0] != kMagic || head[1] == kVersion) return {};
  return "the bus at " + paths.folder + " was started by another canhil (its state is version " +
         std::to_string(head[1]) + ", this canhil's " + std::to_string(kVersion) +
         "): stop it (`canhil bus down`) and start it again";
}

}  // namespace

std::unique_ptr<MappedState> require_state(const BusPaths& paths) {
  if (!broker_alive(paths)) {
    throw BusError("no user-space CAN bus runs at " + paths.folder + ": start one with `canhil bus up vcan0`");
  }
  auto mapped = MappedState::open(paths);
  if (mapped) return mapped;
  if (const std::string other = of_another_canhil(paths); !other.empty()) throw BusError(other);
  throw BusError("the bus at " + paths.folder + " has no state file: stop it (`canhil bus down`) and start it again");
}

namespace {

std::string filter_text(const Socket& s) {
  if (s.filter_count == 0) return "no filter (receives nothing)";
  std::ostringstream out;
  for (std::uint32_t f = 0; f < s.filter_count && f < 4; ++f) {
    char one[48];
    const bool inv = (s.filters[f].can_id & CAN_INV_FILTER) != 0;
    std::snprintf(one, sizeof one, "%s%03X%s%X", f > 0 ? "," : "", s.filters[f].can_id & ~CAN_INV_FILTER,
                  inv ? "~" : ":", s.filters[f].can_mask);
    out << one;
  }
  if (s.filter_count > 4) out << ",... (" << s.filter_count << ")";
  return out.str();
}

}  // namespace

BusPaths BusPaths::current() {
  char folder[256];
  if (!bus_folder(folder, sizeof folder)) throw BusError("CANHIL_BUS_DIR is longer than 255 characters");
  BusPaths p;
  p.folder = folder;
  p.socket = p.folder + "/bus.sock";
  p.state = p.folder + "/state";
  if (p.socket.size() >= sizeof(sockaddr_un{}.sun_path)) {
    throw BusError("the bus folder " + p.folder +
                   " is too long for a socket's path (at most 98 characters): set CANHIL_BUS_DIR to a shorter one");
  }
  return p;
}

std::unique_ptr<MappedState> MappedState::open(const BusPaths& paths) {
  const int fd = ::open(paths.state.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return nullptr;
  struct stat st {};
  if (fstat(fd, &st) != 0 || static_cast<std::size_t>(st.st_size) < sizeof(State)) {
    close(fd);
    return nullptr;
  }
  void* p = mmap(nullptr, sizeof(State), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (p == MAP_FAILED) return nullptr;
  auto* s = static_cast<State*>(p);
  if (s->magic != kMagic || s->version != kVersion) {
    munmap(p, sizeof(State));
    return nullptr;
  }
  return std::unique_ptr<MappedState>(new MappedState(s));
}

MappedState::~MappedState() { munmap(state_, sizeof(State)); }

BrokerSpin::BrokerSpin(const BusPaths& paths, std::uint32_t us) : mapped_(MappedState::open(paths)) {
  if (!mapped_) throw BusError("no user-space CAN bus at " + paths.folder + " to ask its broker to spin");
  word_ = spin_word(getpid(), us);
  mapped_->state().spin.store(word_, std::memory_order_release);
}

BrokerSpin::~BrokerSpin() {
  // Another run may have taken the bus over since: its setting stays.
  std::uint64_t mine = word_;
  mapped_->state().spin.compare_exchange_strong(mine, 0, std::memory_order_acq_rel);
}

bool broker_alive(const BusPaths& paths) {
  const int fd = connect_to(paths);
  if (fd < 0) return false;
  close(fd);
  return true;
}

void check_interface_name(const std::string& name) {
  if (name.empty() || name.size() > 15) {
    throw BusError("interface name '" + name + "': give 1 to 15 characters, as the kernel's (vcan0)");
  }
  for (const char ch : name) {
    if (ch == '/' || ch == ':' || ch <= ' ' || ch == 127) {
      throw BusError("interface name '" + name + "': no '/', ':' or white space, as the kernel's");
    }
  }
}

pid_t start_broker(const BusPaths& paths, const BrokerOptions& options) {
  if (mkdir(paths.folder.c_str(), 0700) != 0 && errno != EEXIST) {
    throw BusError("cannot create the bus folder " + paths.folder + ": " + errno_text(errno));
  }
  struct stat st {};
  if (lstat(paths.folder.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != getuid() ||
      (st.st_mode & 077) != 0) {
    throw BusError(
        "the bus folder " + paths.folder +
        " is not a folder of yours that only you can open (mode 0700): remove it, or set CANHIL_BUS_DIR to another");
  }
  if (broker_alive(paths)) throw BusError("a user-space CAN bus already runs at " + paths.folder);
  // The files of a broker that died (a crashed run) are reclaimed.
  unlink(paths.socket.c_str());
  unlink(paths.state.c_str());

  const int fd = ::open(paths.state.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) throw BusError("cannot create " + paths.state + ": " + errno_text(errno));
  if (ftruncate(fd, sizeof(State)) != 0) {
    const int e = errno;
    close(fd);
    throw BusError("cannot size " + paths.state + ": " + errno_text(e));
  }
  void* p = mmap(nullptr, sizeof(State), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (p == MAP_FAILED) throw BusError("cannot map " + paths.state + ": " + errno_text(errno));
  auto* state = static_cast<State*>(p);
  state->version = kVersion;
  state->grace_us = options.grace_us;
  state->patience_us = std::max(options.patience_us, options.grace_us);
  state->backlog_frames = options.backlog_frames;

  const int listen_fd = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  std::snprintf(a.sun_path, sizeof a.sun_path, "%s", paths.socket.c_str());
  const mode_t old = umask(077);
  const bool bound = bind(listen_fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 && listen(listen_fd, 128) == 0;
  umask(old);
  if (!bound) {
    const int e = errno;
    close(listen_fd);
    munmap(p, sizeof(State));
    throw BusError("cannot listen at " + paths.socket + ": " + errno_text(e));
  }
  const pid_t child = fork();
  if (child < 0) throw BusError(std::string("cannot start the bus's broker: ") + errno_text(errno));
  if (child == 0) {
    // Nothing of its starter's but the listening socket: a descriptor kept here
    // (a worker's pipe to its batch, a caller's socket) would stay open as long
    // as the broker lives, and its other end would never see it close.
    if (listen_fd > 3) close_range(3, static_cast<unsigned>(listen_fd) - 1, 0);
    close_range(static_cast<unsigned>(listen_fd) + 1, ~0U, 0);
    setsid();
    signal(SIGINT, SIG_IGN);
    signal(SIGPIPE, SIG_IGN);
    state->broker_pid = getpid();
    const RealtimeGot got = take_realtime(options.rt_priority);
    state->rt_priority = got.priority;
    state->memory_locked = got.memory_locked ? 1 : 0;
    std::atomic_thread_fence(std::memory_order_release);
    state->magic = kMagic;
    run_broker(listen_fd, *state, options);
    unlink(paths.socket.c_str());
    unlink(paths.state.c_str());
    _exit(0);
  }
  close(listen_fd);
  // The broker is ready to accept once listen() returned; its state is ready once it wrote its pid.
  for (int k = 0; k < 2000 && reinterpret_cast<volatile std::uint32_t&>(state->magic) != kMagic; ++k) usleep(500);
  munmap(p, sizeof(State));
  return child;
}

std::vector<std::string> add_interfaces(const BusPaths& paths, const std::vector<std::string>& names) {
  for (const std::string& n : names) check_interface_name(n);
  auto mapped = require_state(paths);
  State& s = mapped->state();
  std::vector<std::string> created;
  s.lock.lock();
  for (const std::string& n : names) {
    if (Interface* i = find_interface(s, n.c_str())) {
      i->up.store(1);
      continue;
    }
    Interface* free = nullptr;
    for (int k = 0; k < kMaxInterfaces && free == nullptr; ++k) {
      if (s.interfaces[k].in_use.load() == 0) {
        free = &s.interfaces[k];
        free->index = kFirstIndex + k;
      }
    }
    if (free == nullptr) {
      s.lock.unlock();
      throw BusError("the bus has " + std::to_string(kMaxInterfaces) +
                     " interfaces already: remove one (`canhil bus down NAME`)");
    }
    std::memset(free->name, 0, sizeof free->name);
    std::memcpy(free->name, n.data(), n.size());
    free->mtu.store(kInterfaceMtu);
    free->frames.store(0);
    free->dropped.store(0);
    free->bit_rate.store(0);  // instant, as a vcan, until `canhil bus link NAME bitrate N`
    free->data_bit_rate.store(0);
    free->restart_ms.store(kDefaultRestartMs);
    free->tx_queue.store(kDefaultTxQueue);
    free->busy_ns.store(0);
    free->wire_ns.store(0);
    free->error_frames.store(0);
    free->driven.store(0);
    free->delivered.store(0);
    free->next_due_ns.store(INT64_MAX);
    free->up.store(1);
    free->in_use.store(1, std::memory_order_release);
    created.push_back(n);
  }
  s.interfaces_seq.fetch_add(1);
  s.lock.unlock();
  ask_broker(paths, kControlInterfacesChanged);
  return created;
}

void set_interface_up(const BusPaths& paths, const std::string& name, bool up) {
  auto mapped = require_state(paths);
  Interface* i = find_interface(mapped->state(), name.c_str());
  if (i == nullptr) throw BusError("the bus has no interface " + name + " (`canhil bus list` lists them)");
  i->up.store(up ? 1 : 0);
  mapped->state().interfaces_seq.fetch_add(1);
  ask_broker(paths, kControlInterfacesChanged);
}

void remove_interfaces(const BusPaths& paths, const std::vector<std::string>& names) {
  auto mapped = require_state(paths);
  State& s = mapped->state();
  std::string missing;
  s.lock.lock();
  for (const std::string& n : names) {
    Interface* i = find_interface(s, n.c_str());
    if (i == nullptr) {
      missing += (missing.empty() ? "" : ", ") + n;
      continue;
    }
    i->up.store(0);
    i->in_use.store(0, std::memory_order_release);
  }
  s.interfaces_seq.fetch_add(1);
  s.lock.unlock();
  ask_broker(paths, kControlInterfacesChanged);
  if (!missing.empty()) throw BusError("the bus has no interface " + missing + " (`canhil bus list` lists them)");
}

void stop_broker(const BusPaths& paths) {
  if (!broker_alive(paths)) return;
  pid_t pid = 0;
  if (auto mapped = MappedState::open(paths)) pid = mapped->state().broker_pid;
  ask_broker(paths, kControlStop);
  // Wait for it to go (its own child: reap it; another's: watch its socket).
  for (int k = 0; k < 400; ++k) {
    if (pid > 0 && waitpid(pid, nullptr, WNOHANG) == pid) break;
    if (!broker_alive(paths) && (pid <= 0 || kill(pid, 0) != 0)) break;
    usleep(5000);
  }
}

std::string describe(const BusPaths& paths) {
  auto mapped = require_state(paths);
  State& s = mapped->state();
  std::ostringstream out;
  out << "bus " << paths.folder << " (broker pid " << s.broker_pid << ", " << scheduling_text(s) << ", grace "
      << s.grace_us / 1000.0 << " ms, patience " << s.patience_us / 1000.0 << " ms, backlog " << s.backlog_frames
      << " frames)\n";
  bool any = false;
  for (const Interface& i : s.interfaces) {
    if (i.in_use.load() == 0) continue;
    any = true;
    out << "  " << i.name << "  index " << i.index << "  " << (i.up.load() != 0 ? "up" : "down") << "  mtu "
        << i.mtu.load() << "  frames " << i.frames.load() << "  dropped " << i.dropped.load() << wire_text(i) << '\n';
  }
  if (!any) out << "  no interfaces (add one: canhil bus up vcan0)\n";
  out << "  waited for full receivers " << s.waits.load() << " time(s), "
      << static_cast<double>(s.waited_us.load()) / 1000.0 << " ms in all, longest "
      << static_cast<double>(s.longest_wait_us.load()) / 1000.0 << " ms\n";
  for (int k = 0; k < kMaxSockets; ++k) {
    const Socket& sk = s.sockets[k];
    if (sk.in_use.load() == 0) continue;
    std::string where = "unbound";
    if (sk.bound != 0) {
      where = "any";
      if (sk.ifindex != 0) {
        const Interface* i = find_interface(s, sk.ifindex);
        where = i != nullptr ? i->name : "index " + std::to_string(sk.ifindex);
      }
    }
    out << "  socket " << k << "  pid " << sk.pid << " (" << program_of(sk.pid) << ")  " << where << "  filters "
        << filter_text(sk) << "  sent " << sk.sent.load() << "  received " << sk.received.load() << "  read "
        << sk.taken.load() << "  dropped " << sk.drops.load() << '\n';
  }
  out << controllers_text(paths);
  return out.str();
}

std::vector<InterfaceCounts> interface_counts(const BusPaths& paths) {
  auto mapped = require_state(paths);
  std::vector<InterfaceCounts> counts;
  for (const Interface& i : mapped->state().interfaces) {
    if (i.in_use.load() == 0) continue;
    counts.push_back({i.name, i.frames.load(), i.dropped.load()});
  }
  return counts;
}

BusWaits broker_waits(const BusPaths& paths) {
  auto mapped = require_state(paths);
  const State& s = mapped->state();
  return {s.waits.load(), s.waited_us.load(), s.longest_wait_us.load()};
}

std::string exec_report(const BusPaths& paths, const std::vector<std::string>& names,
                        const std::vector<InterfaceCounts>& before, bool own_bus) {
  std::ostringstream out;
  for (const InterfaceCounts& now : interface_counts(paths)) {
    if (std::find(names.begin(), names.end(), now.name) == names.end()) continue;
    std::uint64_t dropped = now.dropped;
    for (const InterfaceCounts& b : before) {
      if (b.name == now.name) dropped -= std::min(dropped, b.dropped);
    }
    if (dropped == 0) continue;
    out << "canhil bus exec: " << dropped << " frame(s) dropped on " << now.name
        << " for receivers whose buffer was full and that read nothing for the bus's grace (each counted on its "
           "socket, SO_RXQ_OVFL; canhil bus up --grace-ms)\n";
  }
  if (const BusWaits w = broker_waits(paths); own_bus && w.count > 0) {
    char line[160];
    std::snprintf(line, sizeof line,
                  "canhil bus exec: the bus waited %llu time(s) for receivers whose backlog was full, %.1f ms in all, "
                  "longest %.1f ms\n",
                  static_cast<unsigned long long>(w.count), static_cast<double>(w.total_us) / 1000.0,
                  static_cast<double>(w.longest_us) / 1000.0);
    out << line;
  }
  return out.str();
}

std::string broker_scheduling(const BusPaths& paths) { return scheduling_text(require_state(paths)->state()); }

void start_broker_detached(const BusPaths& paths, const BrokerOptions& options) {
  const pid_t middle = fork();
  if (middle < 0) throw BusError("cannot start the bus's broker: " + errno_text(errno));
  if (middle == 0) {
    std::fflush(nullptr);
    if (std::freopen("/dev/null", "r", stdin) == nullptr || std::freopen("/dev/null", "w", stdout) == nullptr ||
        std::freopen("/dev/null", "w", stderr) == nullptr) {
      _exit(1);
    }
    try {
      start_broker(paths, options);
    } catch (const BusError&) {
      _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(middle, &status, 0);
  for (int k = 0; k < 400 && !broker_alive(paths); ++k) usleep(5000);
  if (!broker_alive(paths)) start_broker(paths, options);  // once more in this process, for its message
}

int run_on_bus(const BusPaths& paths, const std::vector<std::string>& command) {
  if (command.empty()) throw BusError("no command to run on the bus");
  const std::string preload = find_preload();
  const pid_t child = fork();
  if (child < 0) throw BusError("cannot start " + command.front() + ": " + errno_text(errno));
  if (child == 0) {
    preload_first(preload);
    setenv("CANHIL_BUS_DIR", paths.folder.c_str(), 1);
    std::vector<char*> argv;
    argv.reserve(command.size() + 1);
    for (const std::string& w : command) argv.push_back(const_cast<char*>(w.c_str()));
    argv.push_back(nullptr);
    execvp(argv[0], argv.data());
    std::fprintf(stderr, "canhil bus exec: cannot run %s: %s\n", argv[0], std::strerror(errno));
    _exit(127);
  }
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction old_int {
  }, old_term{};
  sigaction(SIGINT, &ignore, &old_int);
  sigaction(SIGTERM, &ignore, &old_term);
  int status = 0;
  while (waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  return status;
}

std::string find_preload() {
  try {
    return find_asset("CANHIL_BUS_PRELOAD", "the bus's preload",
                      {std::filesystem::path("..") / CANHIL_INSTALL_LIBDIR / "libcanhil-bus.so"},
                      CANHIL_BUILD_BUS_PRELOAD, "canhil_bus_preload")
        .string();
  } catch (const SetupError& e) {
    throw BusError(e.what());
  }
}

void join_bus_if_needed(char** argv) {
  if (hooks().loaded()) return;                             // on it already
  if (std::getenv("CANHIL_BUS_JOINED") != nullptr) return;  // tried once: the kernel answers
  const int probe = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (probe >= 0) {
    close(probe);
    return;  // the kernel has CAN: its interfaces are the ones
  }
  const BusPaths paths = BusPaths::current();
  if (!broker_alive(paths)) return;
  if (const std::string other = of_another_canhil(paths); !other.empty()) {
    // Its preload would not join it: the kernel answers, without CAN.
    std::fprintf(stderr, "%s: %s\n", argv[0], other.c_str());
    return;
  }
  std::string preload;
  try {
    preload = find_preload();
  } catch (const BusError&) {
    return;  // no preload built or installed: the kernel answers, as without a bus
  }
  const std::string before = current_preload();
  preload_first(preload);
  setenv("CANHIL_BUS_JOINED", "1", 1);
  setenv("CANHIL_BUS_DIR", paths.folder.c_str(), 1);
  std::fprintf(stderr, "%s: this kernel has no CAN; running on canhil's user-space bus at %s\n", argv[0],
               paths.folder.c_str());
  std::vector<std::string> arguments;
  for (char** a = argv; *a != nullptr; ++a) arguments.emplace_back(*a);
  start_again(std::move(arguments));
  unsetenv("CANHIL_BUS_JOINED");  // it could not start again: go on without the bus
  if (before.empty()) {
    unsetenv("LD_PRELOAD");
  } else {
    setenv("LD_PRELOAD", before.c_str(), 1);
  }
}

}  // namespace canhil::userbus
