// The broker's wait for a full receiver (userbus/src/broker_system.hpp): it
// follows the receiver, not the clock alone. Each case is a receiver process
// in one state (reading, runnable but not reading, sleeping, stopped) on a
// connection whose buffer is full; what is checked is the verdict, never how
// long it took, so that it holds on a busy machine (issue 52: a receiver that
// is runnable but not running for longer than the grace lost frames).
#include "broker_system.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cstdint>

#include <cstring>
#include "canhil/base/process.hpp"

namespace {

namespace ub = canhil::userbus;

double now_s() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

/// A connection whose broker end's buffer is full, and a receiver process on
/// the other end that runs a behaviour (given its end and its count of
/// records read, in memory both share: Socket::taken's stand-in) and then
/// waits to be killed.
class FullReceiver : public ::testing::Test {
 protected:
  using Taken = std::atomic<std::uint64_t>;
  template <typename Behaviour>
  void start(Behaviour behaviour) {
    void* shared = mmap(nullptr, sizeof(Taken), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    ASSERT_NE(shared, MAP_FAILED);
    taken_ = new (shared) Taken(0);
    int ends[2];
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, ends), 0);
    broker_end_ = ends[0];
    const int size = 4096;
    setsockopt(broker_end_, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
    char record[32] = {};
    while (send(broker_end_, record, sizeof record, MSG_DONTWAIT) > 0) {
    }
    ASSERT_EQ(errno, EAGAIN) << "the buffer fills";
    receiver_ = fork();
    if (receiver_ == 0) {
      close(broker_end_);
      behaviour(ends[1], *taken_);
      for (;;) pause();
    }
    close(ends[1]);
  }
  bool room_came(std::uint32_t grace_us, std::uint32_t patience_us) {
    return ub::room_came(broker_end_, receiver_, *taken_, grace_us, patience_us);
  }
  void TearDown() override {
    if (receiver_ > 0) {
      kill(receiver_, SIGKILL);
      waitpid(receiver_, nullptr, 0);
    }
    if (broker_end_ >= 0) close(broker_end_);
    if (taken_ != nullptr) munmap(taken_, sizeof(Taken));
  }
  int broker_end_ = -1;
  pid_t receiver_ = 0;
  Taken* taken_ = nullptr;
};

/// One record read, counted.
void read_one(int fd, std::atomic<std::uint64_t>& taken) {
  char record[32];
  if (read(fd, record, sizeof record) > 0) taken.fetch_add(1);
}

/// Runnable all along (a busy loop) for `seconds`.
void busy(double seconds) {
  const double until = now_s() + seconds;
  while (now_s() < until) {
  }
}

TEST_F(FullReceiver, RunnableButNotYetReadingPastTheGraceIsWaitedFor) {
  // 0.2 s busy is twenty graces of 10 ms: a fixed grace dropped here. Then
  // it reads its whole buffer, as candump does once it runs.
  start([](int fd, std::atomic<std::uint64_t>& taken) {
    busy(0.2);
    for (int k = 0; k < 1000; ++k) read_one(fd, taken);
  });
  EXPECT_TRUE(room_came(10000, 5000000));
  char record[32] = {};
  EXPECT_GT(send(broker_end_, record, sizeof record, MSG_DONTWAIT), 0) << "the reads made room";
}

TEST_F(FullReceiver, EachRecordReadRenewsTheGrace) {
  // A slow reader asleep 20 ms between its reads, a grace of 30 ms: it
  // lives only by its reads, each of which renews the grace until its
  // buffer has room (AF_UNIX: a quarter full), several graces later.
  start([](int fd, std::atomic<std::uint64_t>& taken) {
    usleep(2000);
    for (int k = 0; k < 1000; ++k) {
      read_one(fd, taken);
      usleep(20000);
    }
  });
  const double start_s = now_s();
  EXPECT_TRUE(room_came(30000, 60000000));
  EXPECT_GT(now_s() - start_s, 0.03) << "longer than one grace";
  EXPECT_GT(taken_->load(), 1U) << "it took several reads";
}

TEST_F(FullReceiver, ASleeperThatReadsNothingForTheGraceIsStuck) {
  start([](int, std::atomic<std::uint64_t>&) {});
  // The sleeper is runnable for a moment after fork: let it reach pause().
  for (int k = 0; k < 500 && canhil::process_runnable(receiver_); ++k) usleep(1000);
  ASSERT_FALSE(canhil::process_runnable(receiver_));
  EXPECT_FALSE(room_came(10000, 5000000));
}

TEST_F(FullReceiver, AStoppedReceiverIsStuck) {
  start([](int, std::atomic<std::uint64_t>&) { busy(100.0); });
  ASSERT_EQ(kill(receiver_, SIGSTOP), 0);
  int status = 0;
  ASSERT_EQ(waitpid(receiver_, &status, WUNTRACED), receiver_);
  ASSERT_TRUE(WIFSTOPPED(status));
  EXPECT_FALSE(canhil::process_runnable(receiver_));
  EXPECT_FALSE(room_came(10000, 5000000));
}

TEST_F(FullReceiver, ABusyLoopThatNeverReadsIsGivenUpAtThePatience) {
  start([](int, std::atomic<std::uint64_t>&) { busy(100.0); });
  EXPECT_TRUE(canhil::process_runnable(receiver_));
  const double start_s = now_s();
  EXPECT_FALSE(room_came(10000, 100000));
  EXPECT_GE(now_s() - start_s, 0.1) << "not before the patience";
}

TEST_F(FullReceiver, AGraceOfZeroDropsAtOnceAsTheKernel) {
  start([](int, std::atomic<std::uint64_t>&) { busy(100.0); });
  EXPECT_FALSE(room_came(0, 5000000));
}

// The wire timer's lead follows the wake-ups it sees, no wall clock read:
// the latest of the last window's and this one's, and a margin, within its
// bounds; a slow moment is forgotten two windows later.
TEST(WireTimerLead, FollowsTheLatestRecentWakeUpWithinItsBounds) {
  using canhil::userbus::WireTimer;
  WireTimer timer;
  EXPECT_EQ(timer.lead(), WireTimer::kLeastLead);
  for (int k = 0; k < 10; ++k) timer.learn(5'000);  // quick wake-ups: the least lead stays
  EXPECT_EQ(timer.lead(), WireTimer::kLeastLead);
  timer.learn(120'000);  // one slow wake-up: the lead covers it, and a margin
  EXPECT_EQ(timer.lead(), 130'000);
  timer.learn(2'000'000);  // a stall: never more than the most lead
  EXPECT_EQ(timer.lead(), WireTimer::kMostLead);
  for (int k = 0; k < 256; ++k) timer.learn(5'000);  // this window and the next quick again
  EXPECT_EQ(timer.lead(), WireTimer::kLeastLead);
}

}  // namespace
