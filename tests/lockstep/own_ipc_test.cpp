// An IPC namespace of one's own, both ways: what the parent made is not seen
// inside, what the child makes inside is not seen outside (nor left behind),
// and the child's user and group stay its own.
#include "canhil/lockstep/own_ipc.hpp"

#include <gtest/gtest.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <thread>

#include "canhil/base/setup_error.hpp"
#include "support/sanitizers.hpp"

namespace canhil::lockstep {
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

TEST(OwnIpc, DirectlyTheParentsSegmentsAreNotSeenAndTheChildsStayInside) {
  if (geteuid() == 0) {
    check_way(IpcWay::kDirect);
    return;
  }
  // Without CAP_SYS_ADMIN the direct way is refused with a SetupError.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(child_checks(IpcWay::kDirect));
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << "refused, as a user may not make one";
}

// In a process of two threads: its exit status 0 when refused with the reason.
int refused_with_threads() {
  try {
    enter_own_ipc_namespace(IpcWay::kUserNamespace);
  } catch (const SetupError& e) {
    return std::string(e.what()).find("more than one thread") != std::string::npos ? 0 : 2;
  }
  return 1;
}

TEST(OwnIpc, ThroughAUserNamespaceTheSameAndTheIdsStayTheProcesss) {
  if (!CANHIL_UNDER_TSAN) {
    check_way(IpcWay::kUserNamespace);
    return;
  }
  // ThreadSanitizer's runtime keeps a thread in every process, and the kernel
  // gives a user namespace to a single-threaded process only: refused, saying so.
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) _exit(refused_with_threads());
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "1: entered, 2: refused without the reason";
}

TEST(OwnIpc, AProcessOfTwoThreadsIsRefusedTheUserNamespaceWithTheReason) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::thread other([] { pause(); });
    other.detach();
    _exit(refused_with_threads());
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "1: entered, 2: refused without the reason";
}

TEST(OwnIpc, TheChosenWayIsTheDirectOneWhenAllowed) {
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      const IpcWay way = enter_own_ipc_namespace();
      _exit(way == (geteuid() == 0 ? IpcWay::kDirect : IpcWay::kUserNamespace) ? 0 : 1);
    } catch (const SetupError&) {
      // Under ThreadSanitizer a user cannot have either way (see above).
      _exit(CANHIL_UNDER_TSAN && geteuid() != 0 ? 0 : 2);
    }
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: the other way taken, 2: none";
}

}  // namespace
}  // namespace canhil::lockstep
