// An IPC namespace of one's own, both ways: what the parent made is not seen
// inside, what the child makes inside is not seen outside (nor left behind),
// and the child's user and group stay its own.
#include "canhil/external/own_ipc.hpp"

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>
#include <string>
#include <thread>

#include "canhil/base/setup_error.hpp"
#include "support/sanitizers.hpp"

namespace canhil::external {
namespace {

// Keys of this test process only (the RTDB's and canhil's own are 0x5x......).
key_t key(int k) { return static_cast<key_t>(0x3E000000 + ((getpid() & 0xFFFF) << 4) + k); }

// In a forked child: enters the namespace `way`, then checks. Its exit status
// is the number of the first check that failed, 0 when none did.
int child_checks(IpcWay way) {
  const uid_t uid = getuid();
  const gid_t gid = getgid();
  try {
    enter_own_ipc_namespace(way);
  } catch (const SetupError&) {
    return 1;
  }
  if (shmget(key(0), 0, 0) >= 0 || errno != ENOENT) return 2;  // the parent's segment: not here
  const int inside = shmget(key(1), 64, IPC_CREAT | IPC_EXCL | 0600);
  if (inside < 0) return 3;
  if (getuid() != uid || getgid() != gid) return 4;
  return 0;  // its segment is left for the namespace's end to remove
}

void check_way(IpcWay way) {
  const int outside = shmget(key(0), 64, IPC_CREAT | IPC_EXCL | 0600);
  ASSERT_GE(outside, 0) << "a segment in this test's namespace";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(child_checks(way));
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  shmctl(outside, IPC_RMID, nullptr);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: not entered, 2: the parent's segment seen, 3: none made, 4: ids changed";
  EXPECT_LT(shmget(key(1), 0, 0), 0) << "the child's segment stayed in its namespace";
}

// What this process may do, asked of the kernel rather than assumed from
// the user: CAP_SYS_ADMIN in its effective set (root in a container may lack
// it), and a user namespace of its own (refused with threads, as under
// ThreadSanitizer, and where the kernel or a seccomp profile refuses it).
bool has_sys_admin() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("CapEff:", 0) == 0) return ((std::stoull(line.substr(7), nullptr, 16) >> 21) & 1U) != 0;
  }
  return false;
}

bool user_namespaces_allowed() {
  const pid_t child = fork();
  if (child == 0) _exit(unshare(CLONE_NEWUSER) == 0 ? 0 : 1);
  int status = 0;
  return child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

// In a forked child: its exit status 0 when `way` is refused with a
// SetupError whose text holds `reason`, 1 when entered, 2 when refused otherwise.
int refused_saying(IpcWay way, const char* reason) {
  try {
    enter_own_ipc_namespace(way);
  } catch (const SetupError& e) {
    return std::string(e.what()).find(reason) != std::string::npos ? 0 : 2;
  }
  return 1;
}

int exit_status_of(const pid_t child) {
  int status = 0;
  if (child <= 0 || waitpid(child, &status, 0) != child || !WIFEXITED(status)) return -1;
  return WEXITSTATUS(status);
}

TEST(OwnIpc, DirectlyTheParentsSegmentsAreNotSeenAndTheChildsStayInside) {
  if (has_sys_admin()) {
    check_way(IpcWay::kDirect);
    return;
  }
  // Without CAP_SYS_ADMIN the direct way is refused with a SetupError.
  const pid_t child = fork();
  if (child == 0) _exit(refused_saying(IpcWay::kDirect, "cannot enter an IPC namespace of its own"));
  EXPECT_EQ(exit_status_of(child), 0) << "refused, as a process without CAP_SYS_ADMIN may not make one";
}

TEST(OwnIpc, ThroughAUserNamespaceTheSameAndTheIdsStayTheProcesss) {
  if (user_namespaces_allowed()) {
    check_way(IpcWay::kUserNamespace);
    return;
  }
  // Refused, saying why and what to do: threads (ThreadSanitizer's runtime
  // keeps one in every process), or a kernel that gives none.
  const pid_t child = fork();
  if (child == 0) {
    const bool threads = CANHIL_UNDER_TSAN != 0;
    _exit(refused_saying(IpcWay::kUserNamespace, threads ? "more than one thread" : "--jobs 1"));
  }
  EXPECT_EQ(exit_status_of(child), 0) << "1: entered, 2: refused without the reason";
}

TEST(OwnIpc, AProcessOfTwoThreadsIsRefusedTheUserNamespaceWithTheReason) {
  const pid_t child = fork();
  if (child == 0) {
    std::thread other([] { pause(); });
    other.detach();
    _exit(refused_saying(IpcWay::kUserNamespace, "more than one thread"));
  }
  EXPECT_EQ(exit_status_of(child), 0) << "1: entered, 2: refused without the reason";
}

TEST(OwnIpc, TheChosenWayIsTheDirectOneWhenAllowed) {
  const bool direct = has_sys_admin();
  const bool user = user_namespaces_allowed();
  const pid_t child = fork();
  if (child == 0) {
    try {
      const IpcWay way = enter_own_ipc_namespace();
      _exit(way == (direct ? IpcWay::kDirect : IpcWay::kUserNamespace) ? 0 : 1);
    } catch (const SetupError&) {
      _exit(!direct && !user ? 0 : 2);  // refused exactly when neither way is open
    }
  }
  EXPECT_EQ(exit_status_of(child), 0) << "1: the other way taken, 2: refused though a way was open";
}

}  // namespace
}  // namespace canhil::external
