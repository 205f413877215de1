// The omni-vision's side of PMan for a run: canhil's own PMan and a PMan
// library loaded at run time (here canhil's libpman.so, which has CAMBADA's
// API) behave the same: the table is made and published before a client can
// attach, one tick activates the client, and canhil counts activations,
// epilogues and deadline misses. The clients are forked processes that do
// what the CAMBADA agent does. Each test uses an agent number of its own.
#include "canhil/pman/masters.hpp"

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include "canhil/base/setup_error.hpp"
#include "canhil/pman/pman_master.h"
#include "pman.h"

namespace canhil::pman {
namespace {

using namespace std::chrono_literals;

int test_agent(int k) { return 700 + static_cast<int>(getpid() % 97) * 3 + k; }

// A forked client: attach as `name`, then per SIGCONT one cycle (a 'C' on the
// pipe) and, unless `late`, PMAN_epilogue; SIGINT ends it.
class Client {
 public:
  Client(int agent, const std::string& name, bool late = false, bool second_team = false) {
    int fds[2];
    EXPECT_EQ(pipe(fds), 0);
    pid_ = fork();
    if (pid_ == 0) {
      ::close(fds[0]);
      sigset_t set;
      sigemptyset(&set);
      sigaddset(&set, SIGCONT);
      sigaddset(&set, SIGINT);
      sigprocmask(SIG_BLOCK, &set, nullptr);
      setenv("AGENT", std::to_string(agent).c_str(), 1);
      if (second_team) {
        setenv("SECOND_RTDB", "1", 1);
      } else {
        unsetenv("SECOND_RTDB");
      }
      for (int i = 0; PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH) != 0; ++i) {
        PMAN_close(PMAN_CLLEAVE);
        if (i > 500) _exit(3);
        usleep(10'000);
      }
      if (PMAN_attach(name.c_str(), getpid()) != 0) _exit(4);
      while (true) {
        int sig = 0;
        sigwait(&set, &sig);
        if (sig == SIGINT) break;
        [[maybe_unused]] const auto w = ::write(fds[1], "C", 1);
        if (!late) PMAN_epilogue(name.c_str());
      }
      PMAN_close(PMAN_CLLEAVE);
      _exit(0);
    }
    ::close(fds[1]);
    fd_ = fds[0];
  }
  ~Client() {
    if (pid_ > 0) {
      kill(pid_, SIGINT);
      waitpid(pid_, nullptr, 0);
    }
    ::close(fd_);
  }
  /// Waits (bounded) for one cycle's report.
  bool cycle() {
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, 10'000) != 1) return false;
    char c = 0;
    return ::read(fd_, &c, 1) == 1 && c == 'C';
  }
  pid_t pid() const { return pid_; }
  /// SIGKILL: dies without a word, and is reaped (its pid no longer exists).
  void die() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
  int fd_ = -1;
};

bool attached(Masters& m, int agent) {
  for (int i = 0; i < 1000; ++i) {
    for (const Process& p : m.query(agent)) {
      if (p.pid != 0) return true;
    }
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

void one_cycle_per_tick(Masters& m) {
  const int agent = test_agent(0);
  const std::string name = "agent" + std::to_string(agent);
  m.open(agent, {name});
  Client client(agent, name);
  ASSERT_TRUE(attached(m, agent)) << "the client found the published table and attached";
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(m.tick(agent), 1);
    ASSERT_TRUE(client.cycle()) << "cycle " << k;
    for (int i = 0; i < 500 && !m.all_idle(agent); ++i) std::this_thread::sleep_for(2ms);
    EXPECT_TRUE(m.all_idle(agent)) << "the epilogue marks it idle, cycle " << k;
  }
  m.tick(agent);  // judges the fifth
  ASSERT_TRUE(client.cycle());
  const auto counts = m.counts(agent);
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].name, name);
  EXPECT_EQ(counts[0].activations, 6u);
  EXPECT_EQ(counts[0].epilogues, 5u);
  EXPECT_EQ(counts[0].deadline_misses, 0u);
  bool listed = false;
  for (const TableView& t : read_tables(agent, agent)) {
    listed = t.agent == agent && t.processes.size() == 1 && t.processes[0].pid == client.pid();
  }
  EXPECT_TRUE(listed) << "read_tables sees the table without attaching";
  m.close_all();
  EXPECT_TRUE(read_tables(agent, agent).empty()) << "closed: the table is gone";
}

TEST(Masters, CanhilsOwnPmanActivatesOnceATickAndCountsEpilogues) { one_cycle_per_tick(*builtin_masters()); }

TEST(Masters, ALoadedPmanLibraryDoesTheSame) { one_cycle_per_tick(*library_masters(CANHIL_TEST_LIBPMAN)); }

TEST(Masters, AClientThatDoesNotEndItsCycleMissesItsDeadline) {
  auto m = builtin_masters();
  const int agent = test_agent(1);
  m->open(agent, {"late"});
  Client client(agent, "late", true);
  ASSERT_TRUE(attached(*m, agent));
  for (int k = 0; k < 3; ++k) {
    m->tick(agent);
    ASSERT_TRUE(client.cycle());
  }
  EXPECT_FALSE(m->all_idle(agent));
  const auto counts = m->counts(agent);
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].epilogues, 0u);
  EXPECT_EQ(counts[0].deadline_misses, 2u) << "the first two activations were judged at the next tick";
}

TEST(Masters, AClientThatDiesIsCountedGoneAndNotActivatedAgain) {
  auto m = builtin_masters();
  const int agent = test_agent(2);
  m->open(agent, {"mortal"});
  {
    Client client(agent, "mortal");
    ASSERT_TRUE(attached(*m, agent));
    EXPECT_EQ(m->tick(agent), 1);
    ASSERT_TRUE(client.cycle());
    client.die();
  }
  EXPECT_EQ(m->tick(agent), 0) << "nobody to wake";
  EXPECT_EQ(m->tick(agent), 0);
  const auto counts = m->counts(agent);
  ASSERT_EQ(counts.size(), 1u);
  EXPECT_EQ(counts[0].activations, 1u);
  EXPECT_EQ(counts[0].gone, 1u) << "its death seen once";
}

TEST(Masters, TheSecondTeamsTablesSitBesideTheFirstsAndItsClientsFindThemWithSecondRtdb) {
  auto first = builtin_masters(0);
  auto second = builtin_masters(1);
  const int agent = test_agent(3);
  const std::string name = "agent" + std::to_string(agent);
  first->open(agent, {name});
  second->open(agent, {name});  // the same agent number: another key
  Client ours(agent, name);
  Client theirs(agent, name, false, true);
  ASSERT_TRUE(attached(*first, agent));
  ASSERT_TRUE(attached(*second, agent));
  EXPECT_EQ(first->query(agent).at(0).pid, ours.pid());
  EXPECT_EQ(second->query(agent).at(0).pid, theirs.pid()) << "SECOND_RTDB=1: the second team's table";
  EXPECT_EQ(second->tick(agent), 1);
  ASSERT_TRUE(theirs.cycle());
  EXPECT_EQ(first->counts(agent).at(0).activations, 0u) << "a tick of one team's table wakes nobody of the other";
  EXPECT_EQ(second->counts(agent).at(0).activations, 1u);
  bool listed_first = false;
  bool listed_second = false;
  for (const TableView& t : read_tables(agent, agent)) {
    listed_first = listed_first || (t.set == 0 && t.key == CANHIL_PMAN_AGENT_KEY(agent));
    listed_second = listed_second || (t.set == 1 && t.key == CANHIL_PMAN_AGENT_KEY(agent) + 0x100);
  }
  EXPECT_TRUE(listed_first && listed_second) << "canhil pman list shows both";
  EXPECT_THROW(builtin_masters(2), SetupError);
}

TEST(Masters, ALibraryWithoutThePmanApiIsNamed) {
  try {
    library_masters("libm.so.6");
    FAIL();
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("has no PMAN_init2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(library_masters("/nonexistent/libpman.so"), SetupError);
}

}  // namespace
}  // namespace canhil::pman
