// The conductor and the time shim together: a real program (lockstep_client)
// runs under the shim while the test moves the virtual clock, and what the
// program's clocks said at each point is checked to the nanosecond. Nothing
// here depends on the machine's speed: the wall clock only bounds a wait.
#include "canhil/lockstep/conductor.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <semaphore.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/child_process.hpp"

namespace {

using namespace std::chrono_literals;
using canhil::lockstep::Conductor;
using canhil::lockstep::ConductorOptions;
using canhil::lockstep::Nanos;
using canhil::test::ChildProcess;

constexpr long long kMonotonicBase = 1'000'000'000'000LL;  // ConductorOptions' default: 1000 s

std::string command(const Conductor& conductor, const std::string& arguments) {
  std::string out = "env";
  for (const std::string& e : conductor.environment(CANHIL_TEST_TIMESHIM, nullptr)) out += " " + e;
  return out + " " + CANHIL_TEST_LOCKSTEP_CLIENT + " " + arguments;
}

// Moves the clock as a run with only external processes would: wait until
// they are quiet, then jump to the earliest wake-up, up to `end`.
std::string drive(Conductor& conductor, Nanos end) {
  for (;;) {
    std::string stuck = conductor.wait_quiet({}, "t = " + std::to_string(conductor.now().count()) + " ns");
    if (!stuck.empty()) return stuck;
    const Nanos next = conductor.next_wakeup();
    if (next > end) {
      conductor.set_time(end);
      return conductor.wait_quiet({}, "the end");
    }
    conductor.set_time(next);
  }
}

// "<what> <ns>" lines, as virtual ns since the run's start.
std::multimap<std::string, long long> said(const std::string& output) {
  std::multimap<std::string, long long> out;
  std::istringstream in(output);
  std::string what;
  long long ns = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    if (words >> what >> ns) out.emplace(what, ns - kMonotonicBase);
  }
  return out;
}

long long at(const std::multimap<std::string, long long>& lines, const std::string& what) {
  const auto it = lines.find(what);
  return it == lines.end() ? -1 : it->second;
}

TEST(Conductor, RemovesTheBoardsOfCanhilsThatWereKilledAndKeepsTheOthers) {
  // A board left by a canhil that ended without removing it (SIGKILL), and
  // one of a canhil that still runs (this process, an index it never uses).
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  waitpid(gone, nullptr, 0);
  const std::string left = "/canhil-lockstep-" + std::to_string(gone) + "-0";
  const std::string running = "/canhil-lockstep-" + std::to_string(getpid()) + "-999999";
  for (const std::string& name : {left, running}) {
    const int fd = shm_open(name.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
    ASSERT_GE(fd, 0) << name;
    close(fd);
  }
  const auto exists = [](const std::string& name) {
    struct stat st {};
    return stat(("/dev/shm" + name).c_str(), &st) == 0;
  };
  { const Conductor conductor; }
  EXPECT_FALSE(exists(left)) << "the killed canhil's board is removed";
  EXPECT_TRUE(exists(running)) << "a running canhil's board stays";
  shm_unlink(running.c_str());
}

TEST(Conductor, GivesEachProcessTheBoardAndThePreloadedShim) {
  Conductor conductor;
  const auto env = conductor.environment("/opt/x/libcanhil-timeshim.so", "/lib/other.so");
  ASSERT_EQ(env.size(), 2u);
  EXPECT_EQ(env[0], "CANHIL_LOCKSTEP=" + conductor.board_name());
  EXPECT_EQ(env[1], "LD_PRELOAD=/opt/x/libcanhil-timeshim.so:/lib/other.so");
  EXPECT_EQ(conductor.next_wakeup(), Nanos(canhil::lockstep::kNoWake)) << "nobody waits yet";
}

TEST(Conductor, ClocksAndSleepsFollowTheVirtualClock) {
  Conductor conductor;
  ChildProcess client(command(conductor, "clocks"), "/tmp/canhil_lockstep_clocks.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u) << client.output();
  ASSERT_EQ(drive(conductor, 3s), "") << client.output();
  const auto lines = said(client.output());
  EXPECT_EQ(at(lines, "start"), 0) << client.output();
  EXPECT_EQ(at(lines, "nanosleep"), 250'000'000);
  EXPECT_EQ(at(lines, "usleep"), 350'000'000);
  EXPECT_EQ(at(lines, "sleep"), 1'350'000'000);
  EXPECT_EQ(at(lines, "clock_nanosleep"), 1'400'000'000) << "an absolute wake-up on CLOCK_MONOTONIC";
  EXPECT_EQ(at(lines, "select"), 1'420'000'000) << "select with no descriptors sleeps";
  EXPECT_NE(client.output().find("realtime 1767225600.000000 time 1767225600"), std::string::npos)
      << "gettimeofday and time start at the run's epoch\n"
      << client.output();
  const auto reports = conductor.processes();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].name, "lockstep_client");
  EXPECT_EQ(reports[0].blocks, 5u) << "one wait per sleep";
}

TEST(Conductor, APollWaitsInVirtualTimeAndWakesWhenDataComes) {
  const std::string fifo = "/tmp/canhil_lockstep_fifo_" + std::to_string(getpid());
  std::remove(fifo.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  Conductor conductor;
  ChildProcess client(command(conductor, "fifo " + fifo), "/tmp/canhil_lockstep_fifo.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  ASSERT_EQ(drive(conductor, 700ms), "") << client.output();
  EXPECT_EQ(at(said(client.output()), "poll-timeout"), 500'000'000) << client.output();
  EXPECT_EQ(at(said(client.output()), "poll-readable"), -1) << "nothing written yet";
  // At 700 ms canhil writes (as it would send a frame) and says so.
  FILE* writer = std::fopen(fifo.c_str(), "w");
  ASSERT_NE(writer, nullptr);
  std::fputc('x', writer);
  std::fflush(writer);
  conductor.nudge();
  ASSERT_EQ(conductor.wait_quiet({}, "the byte"), "") << client.output();
  ASSERT_EQ(drive(conductor, 800ms), "");
  std::fclose(writer);
  EXPECT_EQ(at(said(client.output()), "poll-readable"), 700'000'000) << client.output();
  std::remove(fifo.c_str());
}

// Each change wakes only the waits it concerns (board.hpp): through ten
// changes for descriptors (frames sent) a sleep and a semaphore's wait sleep
// on, a poll looks each time; canhil's post wakes the semaphore's waiter; and
// one process's sem_post wakes another's sem_wait in the instant it was made,
// though canhil changed nothing then (the next change was the poll's timeout
// at 500 ms).
TEST(Conductor, AChangeWakesOnlyTheWaitsItConcerns) {
  const std::string tag = std::to_string(getpid());
  const std::string fifo = "/tmp/canhil_lockstep_kinds_" + tag;
  const std::string told = "/canhil-test-told-" + tag;      // posted by the test
  const std::string passed = "/canhil-test-passed-" + tag;  // posted by a process
  std::remove(fifo.c_str());
  sem_unlink(told.c_str());
  sem_unlink(passed.c_str());
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  sem_t* told_sem = sem_open(told.c_str(), O_CREAT, 0600, 0);
  ASSERT_NE(told_sem, SEM_FAILED);
  Conductor conductor;
  ChildProcess sleeper(command(conductor, "sleeper"), "/tmp/canhil_lockstep_sleeper.log");
  ChildProcess poller(command(conductor, "fifo " + fifo), "/tmp/canhil_lockstep_poller.log");
  ChildProcess waiter(command(conductor, "sem-wait " + told), "/tmp/canhil_lockstep_sem_wait.log");
  ChildProcess poster(command(conductor, "sem-post " + passed), "/tmp/canhil_lockstep_sem_post.log");
  ChildProcess receiver(command(conductor, "sem-wait " + passed), "/tmp/canhil_lockstep_sem_receive.log");
  ASSERT_EQ(conductor.wait_attached(5, 10s), 5u);
  ASSERT_EQ(conductor.wait_quiet({}, "their first waits"), "");
  const auto blocks = [&conductor](const ChildProcess& p) {
    for (const canhil::lockstep::ProcessReport& r : conductor.processes()) {
      if (r.pid == p.pid()) return r.blocks;
    }
    return std::uint64_t{0};
  };
  const std::array<std::uint64_t, 3> before{blocks(sleeper), blocks(poller), blocks(waiter)};
  for (int k = 0; k < 10; ++k) {
    conductor.nudge(canhil::lockstep::kDescriptors);
    ASSERT_EQ(conductor.wait_quiet({}, "frames sent"), "");
  }
  // A wait looks again on its own after a second of wall time: a slow machine
  // may add one; every change would add ten.
  EXPECT_LT(blocks(sleeper), before[0] + 5) << "a sleep sleeps through changes to descriptors";
  EXPECT_LT(blocks(waiter), before[2] + 5) << "and so does a semaphore's wait";
  EXPECT_GE(blocks(poller), before[1] + 10) << "a poll looks at each";
  ASSERT_EQ(sem_post(told_sem), 0);  // the test has no shim: it says what it did
  conductor.nudge(canhil::lockstep::kSemaphores);
  ASSERT_EQ(conductor.wait_quiet({}, "the post"), "");
  EXPECT_EQ(at(said(waiter.output()), "posted"), 0) << waiter.output();
  ASSERT_EQ(drive(conductor, 1200ms), "") << receiver.output();
  EXPECT_EQ(at(said(poster.output()), "post"), 300'000'000) << poster.output();
  EXPECT_EQ(at(said(receiver.output()), "posted"), 300'000'000) << receiver.output();
  EXPECT_EQ(at(said(sleeper.output()), "slept"), 1'000'000'000) << sleeper.output();
  sem_close(told_sem);
  sem_unlink(told.c_str());
  sem_unlink(passed.c_str());
  std::remove(fifo.c_str());
}

// A second preload tells the shim what it cannot see (canhil/lockstep/
// shim_hook.h): a descriptor made readable in user space wakes a thread that
// waits for it, in the instant it happened; frames it sent are counted.
TEST(Conductor, APreloadsHookWakesAWaitForItsDescriptorAndCountsItsFrames) {
  Conductor conductor;
  ChildProcess client(command(conductor, "hook"), "/tmp/canhil_lockstep_hook.log");
  ASSERT_GE(conductor.wait_attached(1, 10s), 1u) << "(its second thread may be there already)";
  ASSERT_EQ(drive(conductor, 1s), "") << client.output();
  const auto lines = said(client.output());
  EXPECT_EQ(at(lines, "written"), 100'000'000) << client.output();
  EXPECT_EQ(at(lines, "readable"), 100'000'000) << "woken by the hook, not by the clock's next move (600 ms)\n"
                                                << client.output();
  EXPECT_EQ(at(lines, "joined"), 600'000'000) << client.output();
  EXPECT_EQ(conductor.frames_sent(), 2u) << "the two frames told, and no write to a pipe";
}

TEST(Conductor, ATimerfdTicksOnTheVirtualClock) {
  Conductor conductor;
  ChildProcess client(command(conductor, "timerfd"), "/tmp/canhil_lockstep_timerfd.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  ASSERT_EQ(drive(conductor, 100ms), "") << client.output();
  std::vector<long long> ticks;
  const auto lines = said(client.output());
  for (auto [it, end] = lines.equal_range("tick"); it != end; ++it) ticks.push_back(it->second);
  EXPECT_EQ(ticks, (std::vector<long long>{10'000'000, 20'000'000, 30'000'000, 40'000'000, 50'000'000}))
      << client.output();
}

TEST(Conductor, TheClockWaitsForANewThread) {
  Conductor conductor;
  ChildProcess client(command(conductor, "thread"), "/tmp/canhil_lockstep_thread.log");
  ASSERT_GE(conductor.wait_attached(1, 10s), 1u) << "(its second thread may be there already)";
  ASSERT_EQ(drive(conductor, 100ms), "") << client.output();
  const auto lines = said(client.output());
  EXPECT_EQ(at(lines, "worker"), 30'000'000) << client.output();
  EXPECT_EQ(at(lines, "joined"), 30'000'000) << "joining is waiting for the other thread, not for time";
}

TEST(Conductor, TheSameProgramGivesTheSameOutputEveryTime) {
  std::string first;
  for (int run = 0; run < 2; ++run) {
    Conductor conductor;
    ChildProcess client(command(conductor, "clocks"), "/tmp/canhil_lockstep_again.log");
    ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
    ASSERT_EQ(drive(conductor, 3s), "");
    client.stop();
    if (run == 0)
      first = client.output();
    else
      EXPECT_EQ(client.output(), first);
  }
  EXPECT_FALSE(first.empty());
}

TEST(Conductor, AProcessThatNeverWaitsIsNamedWithWhatCanhilWaitedFor) {
  ConductorOptions options;
  options.answer_limit = 300ms;
  options.busy_limit = 900ms;  // it computes for ever: named after the busy limit
  Conductor conductor(options);
  ChildProcess client(command(conductor, "spin"), "/tmp/canhil_lockstep_spin.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  const std::string stuck = conductor.wait_quiet({}, "the trigger message at t = 0.010 s");
  EXPECT_NE(stuck.find("lockstep_client (pid "), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("kept running and did not wait again"), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("after the trigger message at t = 0.010 s"), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("0.900 s of wall time"), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("still computing on the CPU: hung in a loop?"), std::string::npos) << stuck;
}

// A process busy on the CPU for longer than the answer limit (a team's agent
// building its maps in its first cycle) is waited for, not named: issue 29's
// CAMBADA agent, stopped after 1 s while it computed.
TEST(Conductor, AProcessComputingLongerThanTheAnswerLimitIsWaitedFor) {
  ConductorOptions options;
  options.answer_limit = 200ms;
  options.busy_limit = 60s;
  Conductor conductor(options);
  ChildProcess client(command(conductor, "compute 700"), "/tmp/canhil_lockstep_compute.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  EXPECT_EQ(drive(conductor, 50ms), "") << client.output();
  EXPECT_NE(client.output().find("slept"), std::string::npos) << client.output();
}

// One blocked where canhil will never wake it (off the CPU) is named within
// the answer limit, however long the busy limit.
TEST(Conductor, AProcessBlockedOffTheCpuIsNamedWithinTheAnswerLimit) {
  ConductorOptions options;
  options.answer_limit = 300ms;
  options.busy_limit = 60s;
  Conductor conductor(options);
  ChildProcess client(command(conductor, "blocked"), "/tmp/canhil_lockstep_blocked.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  const std::string stuck = conductor.wait_quiet({}, "the frame at 10 ms");
  EXPECT_NE(stuck.find("lockstep_client (pid "), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("0.300 s of wall time"), std::string::npos) << stuck;
  EXPECT_NE(stuck.find("not on the CPU: blocked on something canhil will not give"), std::string::npos) << stuck;
}

TEST(Conductor, CanhilsOwnConditionIsWaitedForAndNamed) {
  ConductorOptions options;
  options.answer_limit = 200ms;
  Conductor conductor(options);
  int asked = 0;
  EXPECT_EQ(conductor.wait_quiet([&] { return ++asked < 3 ? std::string("agent1's epilogue") : std::string(); }, "x"),
            "");
  EXPECT_EQ(asked, 3);
  const std::string stuck = conductor.wait_quiet([] { return std::string("agent1's epilogue"); }, "the frame at 33 ms");
  EXPECT_EQ(
      stuck,
      "canhil waited 0.200 s of wall time after the frame at 33 ms for agent1's epilogue (not on the CPU: blocked "
      "on something canhil will not give)");
}

// canhil's own socket in the waits below (two connected datagram sockets,
// closed with it), and a conductor that looks for `spin` before it sleeps.
struct SocketPair {
  int ends[2] = {-1, -1};
  SocketPair() { EXPECT_EQ(socketpair(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0, ends), 0); }
  ~SocketPair() {
    close(ends[0]);
    close(ends[1]);
  }
  SocketPair(const SocketPair&) = delete;
  SocketPair& operator=(const SocketPair&) = delete;
};

ConductorOptions looking_for(Nanos spin, Nanos answer_limit) {
  ConductorOptions options;
  options.answer_limit = answer_limit;
  options.spin = spin;
  return options;
}

TEST(Conductor, ItLooksForAFrameOnItsSocketBeforeItSleeps) {
  // canhil's own condition: a frame in flight, written 20 ms into the wait.
  const auto wait_for_a_frame = [](Nanos spin, std::uint64_t* answered, std::uint64_t* slept) {
    const SocketPair socket;
    Conductor conductor(looking_for(spin, 30s));
    std::thread writer([&] {
      std::this_thread::sleep_for(20ms);
      ASSERT_EQ(write(socket.ends[1], "x", 1), 1);
    });
    const auto frame_here = [&] {
      pollfd p{socket.ends[0], POLLIN, 0};
      return poll(&p, 1, 0) > 0 ? std::string() : std::string("the frame");
    };
    EXPECT_EQ(conductor.wait_quiet(frame_here, "the frame at 10 ms", std::nullopt, socket.ends[0]), "");
    writer.join();
    *answered = conductor.looks_answered();
    *slept = conductor.sleeps();
  };
  std::uint64_t answered = 0;
  std::uint64_t slept = 0;
  // Looking for up to 10 s (giving way to the writer): it comes during the look.
  wait_for_a_frame(10s, &answered, &slept);
  EXPECT_EQ(answered, 1U);
  EXPECT_EQ(slept, 0U);
  // Not looking: the wait sleeps until it comes.
  wait_for_a_frame(Nanos{0}, &answered, &slept);
  EXPECT_EQ(answered, 0U);
  EXPECT_GE(slept, 1U);
}

TEST(Conductor, ItsLooksAskWhatArrivedInMemoryInsteadOfPollingWhenTold) {
  // A descriptor that never becomes readable, and canhil's own condition met
  // only once `arrived` has been asked three times (the bus's counts in
  // memory, on the user-space bus): polled alone, the wait would end at its
  // limit with canhil still waiting. Looking, the third look answers; not
  // looking (spin 0), each turn asks once and sleeps a short while.
  for (const Nanos spin : {Nanos(10s), Nanos{0}}) {
    const SocketPair socket;
    Conductor conductor(looking_for(spin, 2s));
    int asked = 0;
    const auto arrived = [&] { return ++asked >= 3; };
    const auto here = [&] { return asked >= 3 ? std::string() : std::string("the frame"); };
    EXPECT_EQ(conductor.wait_quiet(here, "the frame at 10 ms", std::nullopt, socket.ends[0], arrived), "");
    EXPECT_EQ(asked, 3);
    EXPECT_EQ(conductor.looks_answered(), 1U);
    EXPECT_EQ(conductor.sleeps(), spin > Nanos{0} ? 0U : 2U);
  }
}

TEST(Conductor, ATeamsSyslogGoesToItsOwnLogInLockstepUnlessItAsksForTheSystems) {
  // Three runs: to its log; to the system's syslog with LOG_PERROR, where
  // glibc's own copy on stderr shows that glibc got the message; to its log
  // with LOG_PERROR, where the line comes once (the shim's, not glibc's too).
  struct Case {
    bool system;
    bool perror;
  };
  for (const Case c : {Case{false, false}, Case{true, true}, Case{false, true}}) {
    Conductor conductor;
    const std::string log = "/tmp/canhil_lockstep_syslog_" + std::to_string(getpid()) + ".log";
    ChildProcess client(std::string(c.system ? "env CANHIL_SYSLOG=system " : "") +
                            command(conductor, c.perror ? "syslog perror" : "syslog"),
                        log);
    const std::string pid = std::to_string(client.pid());
    ASSERT_EQ(conductor.wait_attached(1, 10s), 1u) << client.output();
    ASSERT_EQ(drive(conductor, 1s), "") << client.output();
    ASSERT_TRUE(client.wait_end(10s).has_value()) << client.output();
    const std::string out = client.output();
    EXPECT_EQ(at(said(out), "logged"), 100'000'000) << out;
    const auto count = [&out](const std::string& line) {
      std::size_t n = 0;
      for (std::size_t at = out.find(line); at != std::string::npos; at = out.find(line, at + 1)) ++n;
      return n;
    };
    // glibc's LOG_PERROR lines: openlog's ident and, with LOG_PID, the pid.
    const std::string head = "teamlog[" + pid + "]: ";
    EXPECT_EQ(count(head + "cycle 42\n"), 1u) << "system " << c.system << ", perror " << c.perror << "\n" << out;
    EXPECT_EQ(count(head + "no map: No such file or directory\n"), 1u) << out;
    EXPECT_EQ(count("hidden by the mask"), 0u) << out;
    EXPECT_EQ(count(head + "fortified too\n"), 1u) << out;
    if (!c.perror) {
      EXPECT_EQ(count("lockstep_client: after closelog\n"), 1u) << "closelog forgets the ident\n" << out;
    }
  }
}

TEST(Conductor, AProcessKilledWithoutAWordIsNoLongerWaitedFor) {
  ConductorOptions options;
  options.answer_limit = 5s;
  Conductor conductor(options);
  ChildProcess client(command(conductor, "spin"), "/tmp/canhil_lockstep_killed.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  client.kill_with(SIGKILL);
  EXPECT_EQ(conductor.wait_quiet({}, "x"), "");
  const auto reports = conductor.processes();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_TRUE(reports[0].gone);
}

}  // namespace

namespace {

TEST(Conductor, ReleasingTheBoardEndsEveryVirtualWaitSoAProcessCanStop) {
  // The run is over: a process that retries an hour's sleep after a signal
  // (as a library's wait does) would wait for a virtual time that never comes,
  // and never see its SIGINT. Released, the sleep ends as if its time had come.
  Conductor conductor;
  ChildProcess client(command(conductor, "patient"), "/tmp/canhil_lockstep_patient.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u) << client.output();
  ASSERT_EQ(drive(conductor, 1s), "") << client.output();
  EXPECT_EQ(at(said(client.output()), "patient"), 0) << client.output();
  EXPECT_FALSE(conductor.released());
  conductor.release();
  EXPECT_TRUE(conductor.released());
  const int status = client.stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << client.output();
  EXPECT_NE(client.output().find("patient woke"), std::string::npos) << client.output();
  EXPECT_EQ(client.output().find("is gone"), std::string::npos) << "a release is no news\n" << client.output();
}

}  // namespace

namespace {

TEST(Conductor, AProcessKilledWithoutAWordWhileCanhilWaitsIsNoLongerWaitedFor) {
  // Killed well into a wait, not at its start: the wait ends quiet, rather
  // than naming it after the answer limit (as it did when the dead were looked
  // for once, 50 ms into a wait).
  ConductorOptions options;
  options.answer_limit = 5s;
  Conductor conductor(options);
  ChildProcess client(command(conductor, "spin"), "/tmp/canhil_lockstep_killed_later.log");
  ASSERT_EQ(conductor.wait_attached(1, 10s), 1u);
  std::thread killer([&client] {
    std::this_thread::sleep_for(300ms);
    client.kill_with(SIGKILL);
  });
  const std::string stuck = conductor.wait_quiet({}, "x");
  killer.join();
  EXPECT_EQ(stuck, "");
}

// A program started with the shim preloaded but outside a run (no board in
// its environment: a team's tool started by hand) keeps the system's calls,
// timeouts included: a sigtimedwait with a timeout once waited for ever.
TEST(Conductor, OutsideARunTheShimKeepsASignalWaitsTimeout) {
  ChildProcess client(
      std::string("env LD_PRELOAD=") + CANHIL_TEST_TIMESHIM + " " + CANHIL_TEST_LOCKSTEP_CLIENT + " sigtimedwait",
      "/tmp/canhil_lockstep_sigtimedwait.log");
  const std::optional<int> status = client.wait_end(30s);  // only bounds the wait: it takes 0.1 s
  ASSERT_TRUE(status.has_value()) << "still waiting after 30 s: " << client.output();
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << client.output();
  EXPECT_NE(client.output().find("sigtimedwait-timeout"), std::string::npos) << client.output();
}

TEST(Conductor, AShellWhoseProgramIsMissingIsNoLongerWaitedFor) {
  // As canhil starts a team's processes: its own child, `sh -c "exec ..."`,
  // reaped only later, so that it stays a zombie while canhil waits.
  ConductorOptions options;
  options.answer_limit = 5s;
  Conductor conductor(options);
  const std::vector<std::string> environment = conductor.environment(CANHIL_TEST_TIMESHIM, nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    for (const std::string& e : environment) putenv(const_cast<char*>(e.c_str()));
    execl("/bin/sh", "sh", "-c", "exec canhil-no-such-program --iface vcan0", static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  conductor.wait_attached(1, 2s);
  EXPECT_EQ(conductor.wait_quiet({}, "x"), "");
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_EQ(WEXITSTATUS(status), 127);
}

}  // namespace
