// A System V IPC namespace of one's own (own_ipc.hpp).
#include "canhil/external/own_ipc.hpp"

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "canhil/base/errno_text.hpp"
#include "canhil/base/setup_error.hpp"

namespace canhil::external {
namespace {

// What a user can do where the kernel refuses a user namespace.
constexpr const char* kRemedy =
    ": run as root, or allow unprivileged user namespaces (Debian: sysctl kernel.unprivileged_userns_clone=1 and "
    "user.max_user_namespaces > 0; Ubuntu 23.10 and later: sysctl kernel.apparmor_restrict_unprivileged_userns=0), "
    "or play these matches one at a time (--jobs 1)";

// `text` into the /proc file `path`, whole, or SetupError.
void write_proc(const char* path, const std::string& text) {
  const int fd = ::open(path, O_WRONLY | O_CLOEXEC);
  const ssize_t n = fd >= 0 ? ::write(fd, text.data(), text.size()) : -1;
  const int e = errno;
  if (fd >= 0) ::close(fd);
  if (n != static_cast<ssize_t>(text.size())) {
    throw SetupError(std::string("cannot write ") + path + " for an IPC namespace of its own (" + errno_text(e) + ")" +
                     kRemedy);
  }
}

}  // namespace

void enter_own_ipc_namespace(IpcWay way) {
  if (way == IpcWay::kDirect) {
    if (::unshare(CLONE_NEWIPC) != 0) {
      throw SetupError("cannot enter an IPC namespace of its own: " + errno_text(errno));
    }
    return;
  }
  // The ids are read before: inside, until the maps are written, they read as the overflow id.
  const uid_t uid = ::getuid();
  const gid_t gid = ::getgid();
  if (::unshare(CLONE_NEWUSER | CLONE_NEWIPC) != 0) {
    const int e = errno;
    if (e == EINVAL) {
      throw SetupError(
          "cannot enter a user namespace for an IPC namespace of its own: the process has more than one thread "
          "(the kernel allows it to a single-threaded process only), or the kernel has no user or IPC namespaces");
    }
    throw SetupError("cannot enter an IPC namespace of its own, directly (no CAP_SYS_ADMIN) nor in a user namespace (" +
                     errno_text(e) + ")" + kRemedy);
  }
  write_proc("/proc/self/setgroups", "deny");  // required before an unprivileged gid_map
  write_proc("/proc/self/uid_map", std::to_string(uid) + " " + std::to_string(uid) + " 1");
  write_proc("/proc/self/gid_map", std::to_string(gid) + " " + std::to_string(gid) + " 1");
}

IpcWay enter_own_ipc_namespace() {
  if (::unshare(CLONE_NEWIPC) == 0) return IpcWay::kDirect;
  if (errno != EPERM) throw SetupError("cannot enter an IPC namespace of its own: " + errno_text(errno));
  enter_own_ipc_namespace(IpcWay::kUserNamespace);
  return IpcWay::kUserNamespace;
}

}  // namespace canhil::external
