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
