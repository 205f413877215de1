// What base/process.hpp says of a thread and a process: the state letter
// of /proc, and whether a process is runnable (what the bus's broker and the
// lockstep conductor ask of a process they wait for).
#include "canhil/base/process.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace {

TEST(ProcessRunnable, AGoneProcessIsNot) {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  waitpid(child, nullptr, 0);
  EXPECT_FALSE(canhil::process_runnable(child));
  EXPECT_FALSE(canhil::process_runnable(0));
  EXPECT_TRUE(canhil::process_runnable(getpid())) << "this thread runs";
}

// ThreadSanitizer turns vfork into fork (no 'D' state to see): the plain and
// ASan builds run this test, the tsan build does not compile it.
#if defined(__SANITIZE_THREAD__)
#define CANHIL_REAL_VFORK 0
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CANHIL_REAL_VFORK 0
#endif
#endif
#ifndef CANHIL_REAL_VFORK
#define CANHIL_REAL_VFORK 1
#endif

#if CANHIL_REAL_VFORK
TEST(ProcessHeldByMachine, AVforkParentIsInAnUninterruptibleWaitAndHeldNotAsleep) {
  // A vfork's parent waits uninterruptibly ('D') until its child execs or
  // ends: what a write to a busy disk looks like, deterministically. The
  // broker waits for such a reader (it comes back by itself), not for one
  // asleep ('S').
  const pid_t child = fork();
  if (child == 0) {
    if (vfork() == 0) {
      usleep(500000);
      _exit(0);
    }
    _exit(0);
  }
  char state = '?';
  for (int k = 0; k < 400 && state != 'D'; ++k) {
    usleep(1000);
    state = canhil::thread_state(child, child);
  }
  EXPECT_EQ(state, 'D');
  EXPECT_TRUE(canhil::process_held_by_machine(child));
  EXPECT_FALSE(canhil::process_runnable(child));
  waitpid(child, nullptr, 0);
  const pid_t sleeper = fork();
  if (sleeper == 0) {
    pause();
    _exit(0);
  }
  for (int k = 0; k < 400 && canhil::thread_state(sleeper, sleeper) != 'S'; ++k) usleep(1000);
  EXPECT_FALSE(canhil::process_held_by_machine(sleeper)) << "asleep: waiting for something else";
  kill(sleeper, SIGKILL);
  waitpid(sleeper, nullptr, 0);
}
#endif

TEST(ThreadState, RunningStoppedEndedAndGone) {
  EXPECT_EQ(canhil::thread_state(getpid(), getpid()), 'R');
  const pid_t child = fork();
  if (child == 0) {
    for (;;) pause();
  }
  ASSERT_EQ(kill(child, SIGSTOP), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, WUNTRACED), child);
  EXPECT_EQ(canhil::thread_state(child, child), 'T');
  ASSERT_EQ(kill(child, SIGKILL), 0);
  for (int k = 0; k < 1000 && canhil::thread_state(child, child) != 'Z'; ++k) usleep(1000);
  EXPECT_EQ(canhil::thread_state(child, child), 'Z') << "ended, not yet reaped";
  waitpid(child, nullptr, 0);
  EXPECT_EQ(canhil::thread_state(child, child), '?') << "gone";
}

}  // namespace
