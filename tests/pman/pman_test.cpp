// PMan: CAMBADA's table layout to the byte; a master (the handle API, or
// CAMBADA's API) and clients in forked processes that do what the CAMBADA
// agent does — attach, sleep until SIGCONT, run a cycle, PMAN_epilogue — and
// report each step through a pipe; scheduling, late and dead clients, deadline
// misses, two masters in one process, a garbled table. Every test has its own
// keys (an AGENT far above any robot's) and must leave no IPC object behind.
#include "pman.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/ipc.h>
#include <sys/sem.h>
#include <sys/shm.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "canhil/pman/pman_master.h"

// The x86_64 layout of CAMBADA's table (measured from CAMBADA's headers with gcc).
static_assert(sizeof(PROC_TRACE_DATA) == 24);
static_assert(offsetof(PROC_TRACE_DATA, etype) == 4 && offsetof(PROC_TRACE_DATA, etime) == 8);
static_assert(sizeof(PROC_TYPE) == 312);
static_assert(offsetof(PROC_TYPE, PROC_name) == 0);
static_assert(offsetof(PROC_TYPE, PROC_id) == 36);
static_assert(offsetof(PROC_TYPE, PROC_period) == 40);
static_assert(offsetof(PROC_TYPE, PROC_phase) == 44);
static_assert(offsetof(PROC_TYPE, PROC_deadline) == 48);
static_assert(offsetof(PROC_TYPE, PROC_pred_name) == 52);
static_assert(offsetof(PROC_TYPE, PROC_succ_index) == 220);
static_assert(offsetof(PROC_TYPE, PROC_pred_mask) == 240);
static_assert(offsetof(PROC_TYPE, PROC_pred_met) == 248);
static_assert(offsetof(PROC_TYPE, PROC_qosdata) == 256);
static_assert(offsetof(PROC_TYPE, PROC_qosupdflag) == 260);
static_assert(offsetof(PROC_TYPE, PROC_last_start) == 264);
static_assert(offsetof(PROC_TYPE, PROC_last_finish) == 280);
static_assert(offsetof(PROC_TYPE, PROC_status) == 296);
static_assert(offsetof(PROC_TYPE, PROC_nact) == 300);
static_assert(offsetof(PROC_TYPE, PROC_ndm) == 304);
static_assert(sizeof(PROC_TABLE_TYPE) == 246272);
static_assert(offsetof(PROC_TABLE_TYPE, nprocs) == 0);
static_assert(offsetof(PROC_TABLE_TYPE, ticks) == 4);
static_assert(offsetof(PROC_TABLE_TYPE, QoSupd) == 8);
static_assert(offsetof(PROC_TABLE_TYPE, DdlnExcpt) == 16);
static_assert(offsetof(PROC_TABLE_TYPE, proc) == 24);
static_assert(offsetof(PROC_TABLE_TYPE, evt_lastindex) == 6264);
static_assert(offsetof(PROC_TABLE_TYPE, evt_firstindex) == 6268);
static_assert(offsetof(PROC_TABLE_TYPE, evt_trace) == 6272);

namespace {

constexpr int kStockSegment = 246272 + PROC_TABLE_SIZE * 4;  // CAMBADA's master, QoS data one int

key_t agent_key(int agent) { return SHMEM_OCAM_PMAN_KEY + 2 * agent; }

struct ClientOptions {
  std::string name;
  int agent = 0;
  bool skip_first_epilogue = false;  // run cycle 1 without PMAN_epilogue (a late client)
  bool exit_after_attach = false;    // die at once (a crashed client)
};

// The forked client: the CAMBADA agent's start-up and loop, with sigwait in
// place of a handler. Reports: W waiting for the master (-18), A attached,
// U name not registered, C a cycle done (after its epilogue), I SIGINT, F failure.
[[noreturn]] void run_client(const ClientOptions& o, int fd) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, PMAN_ACTIVATE_SIG);
  sigaddset(&set, SIGINT);
  sigprocmask(SIG_BLOCK, &set, nullptr);
  auto report = [fd](char c) { (void)!write(fd, &c, 1); };
  setenv("AGENT", std::to_string(o.agent).c_str(), 1);
  bool told = false;
  for (int r; (r = PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH)) != 0;) {
    if (r != -18) report('F'), _exit(2);
    if (!told) report('W'), told = true;
    PMAN_close(PMAN_CLFREE);  // what the CAMBADA agent does after -18: must be harmless
    usleep(10000);
  }
  const int attached = PMAN_attach(o.name.c_str(), getpid());
  report(attached == 0 ? 'A' : attached == -2 ? 'U' : 'F');
  if (attached != 0) _exit(3);
  if (o.exit_after_attach) _exit(0);
  for (int cycle = 1;; ++cycle) {
    int sig = 0;
    sigwait(&set, &sig);
    if (sig == SIGINT) {
      PMAN_close(PMAN_CLLEAVE);
      report('I');
      _exit(0);
    }
    if (!(o.skip_first_epilogue && cycle == 1)) PMAN_epilogue(o.name.c_str());
    report('C');
  }
}

class Client {
 public:
  explicit Client(const ClientOptions& o) {
    int fds[2];
    if (pipe(fds) != 0) std::abort();
    std::fflush(nullptr);  // the child must not write the parent's buffered output again
    pid_ = fork();
    if (pid_ == 0) {
      close(fds[0]);
      run_client(o, fds[1]);
    }
    close(fds[1]);
    fd_ = fds[0];
  }
  ~Client() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    close(fd_);
  }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // The next report, or 0 if none comes within timeout_ms.
  char next(int timeout_ms = 5000) const {
    pollfd p{fd_, POLLIN, 0};
    char c = 0;
    if (poll(&p, 1, timeout_ms) == 1 && read(fd_, &c, 1) == 1) return c;
    return 0;
  }
  // Reaps the client; its wait status.
  int wait_exit() {
    int status = -1;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int fd_ = -1;
};

class Pman : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    agent_ = 0x100000 + ((getpid() & 0xFFFF) << 6) + 2 * ++counter;  // this test's agents: agent_, agent_ + 1
    setenv("AGENT", std::to_string(agent_).c_str(), 1);
    name_ = "agent" + std::to_string(agent_);
  }
  void TearDown() override {
    EXPECT_EQ(p_table, nullptr) << "the test left CAMBADA's current table open";
    for (int agent : {agent_, agent_ + 1}) {  // nothing may be left behind; remove it if it was
      const int shm = shmget(agent_key(agent), 0, 0);
      const int sem = semget(agent_key(agent), 0, 0);
      EXPECT_LT(shm, 0) << "agent " << agent << "'s table was not removed";
      EXPECT_LT(sem, 0) << "agent " << agent << "'s semaphore was not removed";
      if (shm >= 0) shmctl(shm, IPC_RMID, nullptr);
      if (sem >= 0) semctl(sem, 0, IPC_RMID);
    }
  }
  canhil_pman* open(int agent) {
    int error = 1;
    canhil_pman* m = canhil_pman_open_master(agent, &error);
    EXPECT_NE(m, nullptr);
    EXPECT_EQ(error, 0);
    return m;
  }
  static PROC_TYPE query(canhil_pman* m, const std::string& name) {
    PROC_TYPE p{};
    EXPECT_EQ(canhil_pman_query(m, name.c_str(), &p), 0) << name;
    return p;
  }
  int agent_ = 0;
  std::string name_;
};

TEST(PmanLayout, ConstantsAreCambadas) {
  EXPECT_EQ(SHMEM_OCAM_PMAN_KEY, 0x9011);
  EXPECT_EQ(SEM_OCAM_PMAN_KEY, 0x9011);
  EXPECT_EQ(SHMEM_FCAM_PMAN_KEY, 0x9010);
  EXPECT_EQ(CANHIL_PMAN_AGENT_KEY(1), 0x9013);
  EXPECT_EQ(CANHIL_PMAN_AGENT_KEY(6), 0x901D);
  EXPECT_EQ(PROC_TABLE_SIZE, 20);
  EXPECT_EQ(PMAN_TRACE_SIZE, 10000);
  EXPECT_EQ(PROC_S_IDLE, 3);
  EXPECT_EQ(PMAN_ACTIVATE_SIG, SIGCONT);
}

TEST_F(Pman, TableIsInitialisedAsCambadasAndPublishedByStart) {
  canhil_pman* m = open(agent_);
  const int shm = shmget(agent_key(agent_), 0, 0);
  const int sem = semget(agent_key(agent_), 0, 0);
  ASSERT_GE(shm, 0);
  ASSERT_GE(sem, 0);
  shmid_ds ds{};
  ASSERT_EQ(shmctl(shm, IPC_STAT, &ds), 0);
  EXPECT_EQ(ds.shm_segsz, static_cast<size_t>(kStockSegment));
  EXPECT_EQ(ds.shm_perm.mode & 0777, 0666);
  EXPECT_EQ(semctl(sem, 0, GETVAL), 0) << "unpublished: clients wait";
  ASSERT_EQ(canhil_pman_start(m), 0);
  EXPECT_EQ(semctl(sem, 0, GETVAL), 1);
  auto* t = static_cast<PROC_TABLE_TYPE*>(shmat(shm, nullptr, SHM_RDONLY));
  ASSERT_NE(reinterpret_cast<intptr_t>(t), -1);
  EXPECT_EQ(t->nprocs, 0);
  EXPECT_EQ(t->QoSupd, nullptr) << "no code address in shared memory";
  for (int i = 0; i < PROC_TABLE_SIZE; ++i) {
    EXPECT_EQ(t->proc[i].PROC_qosdata, 246272 + 4 * i);
    EXPECT_EQ(t->proc[i].PROC_succ_index[0], PMAN_NOINDEX);
    EXPECT_EQ(t->proc[i].PROC_status, PROC_S_EMPTY);
  }
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  EXPECT_EQ(t->nprocs, 1);
  EXPECT_EQ(t->proc[0].PROC_status, PROC_S_IDLE);
  EXPECT_EQ(t->proc[0].PROC_qosupdflag, 1);
  shmdt(t);
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, ClientRunsExactlyOneCyclePerTick) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  Client c({name_, agent_});
  ASSERT_EQ(c.next(), 'A');
  EXPECT_EQ(query(m, name_).PROC_id, c.pid());
  constexpr int kTicks = 10;
  for (int k = 0; k < kTicks; ++k) {
    ASSERT_EQ(canhil_pman_tick(m), 1);
    ASSERT_EQ(c.next(), 'C') << "tick " << k;
  }
  EXPECT_EQ(c.next(100), 0) << "one cycle per tick, no more";
  const PROC_TYPE p = query(m, name_);
  EXPECT_EQ(p.PROC_nact, static_cast<unsigned>(kTicks));
  EXPECT_EQ(p.PROC_status, PROC_S_IDLE);
  EXPECT_EQ(p.PROC_ndm, 0u);
  EXPECT_TRUE(timercmp(&p.PROC_last_finish, &p.PROC_last_start, >=));
  EXPECT_EQ(canhil_pman_get_counters(m).activations, static_cast<unsigned long long>(kTicks));
  EXPECT_EQ(canhil_pman_close(m), 0);
  EXPECT_EQ(c.next(), 'I');
}

TEST_F(Pman, PeriodTwoPhaseOneRunsOnOddTicks) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 2, 1, 10000), 0);
  Client c({name_, agent_});
  ASSERT_EQ(canhil_pman_start(m), 0);
  ASSERT_EQ(c.next(), 'A');
  for (int tick = 0; tick < 8; ++tick) {
    const bool due = tick % 2 == 1;
    ASSERT_EQ(canhil_pman_tick(m), due ? 1 : 0) << "tick " << tick;
    if (due) {
      ASSERT_EQ(c.next(), 'C') << "tick " << tick;
    }
    EXPECT_EQ(query(m, name_).PROC_nact, static_cast<unsigned>((tick + 1) / 2)) << "tick " << tick;
  }
  EXPECT_EQ(c.next(50), 0);
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, ClientStartedFirstWaitsAndAttachesOncePublished) {
  Client c({name_, agent_});
  ASSERT_EQ(c.next(), 'W') << "no master: -18";
  EXPECT_LT(shmget(agent_key(agent_), 0, 0), 0) << "a waiting client creates nothing";
  canhil_pman* m = open(agent_);
  EXPECT_EQ(c.next(200), 0) << "the table is not published before its processes are registered";
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  ASSERT_EQ(c.next(), 'A');
  ASSERT_EQ(canhil_pman_tick(m), 1);
  EXPECT_EQ(c.next(), 'C');
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, ClientErrorsWithoutMasterOrRegistration) {
  EXPECT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH), -18);
  EXPECT_EQ(p_table, nullptr);
  EXPECT_EQ(PMAN_close(PMAN_CLFREE), -111);
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_start(m), 0);
  ASSERT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH), 0);
  EXPECT_EQ(PMAN_attach("nobody", getpid()), -2);
  EXPECT_EQ(PMAN_epilogue("nobody"), -2);
  EXPECT_EQ(PMAN_attach(nullptr, getpid()), -2);
  EXPECT_EQ(PMAN_attach(std::string(40, 'x').c_str(), getpid()), -2);
  EXPECT_EQ(PMAN_close(PMAN_CLLEAVE), 0);
  EXPECT_EQ(PMAN_close(PMAN_CLLEAVE), -111);
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, AgentMustBeSet) {
  unsetenv("AGENT");
  testing::internal::CaptureStderr();
  EXPECT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH), PMAN_E_AGENT);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("AGENT is not set"), std::string::npos);
  for (const char* bad : {"x", "-1", "1x", "99999999999"}) {
    setenv("AGENT", bad, 1);
    testing::internal::CaptureStderr();
    EXPECT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_NEW), PMAN_E_AGENT) << bad;
    testing::internal::GetCapturedStderr();
  }
  int error = 0;
  EXPECT_EQ(canhil_pman_open_master(-1, &error), nullptr);
  EXPECT_EQ(error, PMAN_E_AGENT);
  EXPECT_EQ(canhil_pman_open_master_keys(IPC_PRIVATE, 1, &error), nullptr);
  EXPECT_EQ(error, PMAN_E_ARG);
  EXPECT_EQ(PMAN_init2(agent_key(agent_), agent_key(agent_), nullptr, 0, 7), PMAN_E_ARG);
}

TEST_F(Pman, ProcaddProcdelRules) {
  canhil_pman* m = open(agent_);
  EXPECT_EQ(canhil_pman_procadd(m, "", 1, 0, 0), PMAN_E_ARG);
  EXPECT_EQ(canhil_pman_procadd(m, nullptr, 1, 0, 0), PMAN_E_ARG);
  EXPECT_EQ(canhil_pman_procadd(m, std::string(PNAME_LEN + 1, 'n').c_str(), 1, 0, 0), PMAN_E_ARG);
  EXPECT_EQ(canhil_pman_procadd(m, "p", 0, 0, 0), PMAN_E_ARG) << "a period of 0 would divide by zero";
  EXPECT_EQ(canhil_pman_procadd(m, std::string(PNAME_LEN, 'n').c_str(), 1, 0, 0), 0) << "the longest name";
  for (int i = 1; i < PROC_TABLE_SIZE; ++i) {
    ASSERT_EQ(canhil_pman_procadd(m, ("p" + std::to_string(i)).c_str(), 1, 0, 0), 0);
  }
  EXPECT_EQ(canhil_pman_procadd(m, "one-more", 1, 0, 0), -2) << "table full";
  EXPECT_EQ(canhil_pman_procdel(m, "p3"), 0);
  EXPECT_EQ(canhil_pman_procdel(m, "p3"), -2);
  EXPECT_EQ(canhil_pman_procadd(m, "p4", 1, 0, 0), -3) << "already registered";
  EXPECT_EQ(canhil_pman_procadd(m, "again", 3, 2, 7), 0) << "the freed slot";
  const PROC_TYPE p = query(m, "again");
  EXPECT_EQ(p.PROC_period, 3);
  EXPECT_EQ(p.PROC_phase, 2);
  EXPECT_EQ(p.PROC_deadline, 7);
  EXPECT_EQ(p.PROC_id, PMAN_NOPID);
  EXPECT_EQ(canhil_pman_query(m, "p3", nullptr), -1);
  EXPECT_EQ(canhil_pman_close(m), 0);
  EXPECT_EQ(canhil_pman_procadd(nullptr, "x", 1, 0, 0), -1);
  EXPECT_EQ(canhil_pman_tick(nullptr), -1);
  EXPECT_EQ(canhil_pman_close(nullptr), -1);
}

TEST_F(Pman, DeadClientIsDeattachedOnRelease) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  Client c({name_, agent_, false, true});
  ASSERT_EQ(c.next(), 'A');
  c.wait_exit();  // reaped: its pid is gone
  EXPECT_EQ(canhil_pman_tick(m), 0);
  const PROC_TYPE p = query(m, name_);
  EXPECT_EQ(p.PROC_id, PMAN_NOPID);
  EXPECT_EQ(p.PROC_status, PROC_S_IDLE);
  EXPECT_EQ(p.PROC_nact, 0u);
  EXPECT_EQ(canhil_pman_get_counters(m).dead_clients, 1u);
  EXPECT_EQ(canhil_pman_tick(m), 0);
  EXPECT_EQ(canhil_pman_get_counters(m).dead_clients, 1u) << "counted once";
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, CloseInterruptsClientsAndRemovesTableAndSemaphore) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  Client c({name_, agent_});
  ASSERT_EQ(c.next(), 'A');
  ASSERT_EQ(canhil_pman_tick(m), 1);
  ASSERT_EQ(c.next(), 'C');
  EXPECT_EQ(canhil_pman_close(m), 0);
  EXPECT_EQ(c.next(), 'I') << "SIGINT";
  const int status = c.wait_exit();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_LT(shmget(agent_key(agent_), 0, 0), 0);
  EXPECT_EQ(errno, ENOENT);
  EXPECT_LT(semget(agent_key(agent_), 0, 0), 0);
  EXPECT_EQ(errno, ENOENT);
}

TEST_F(Pman, DeadlineMissWhenTheEpilogueComesAfterTheNextTick) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  Client c({name_, agent_, true});
  ASSERT_EQ(c.next(), 'A');
  ASSERT_EQ(canhil_pman_tick(m), 1);
  ASSERT_EQ(c.next(), 'C');  // cycle 1 ends without its epilogue
  EXPECT_EQ(query(m, name_).PROC_status, PROC_S_READY);
  EXPECT_EQ(query(m, name_).PROC_ndm, 0u);
  ASSERT_EQ(canhil_pman_tick(m), 1) << "activated again, as CAMBADA does";
  EXPECT_EQ(query(m, name_).PROC_ndm, 1u);
  ASSERT_EQ(c.next(), 'C');  // cycle 2 with its epilogue
  ASSERT_EQ(canhil_pman_tick(m), 1);
  ASSERT_EQ(c.next(), 'C');
  const PROC_TYPE p = query(m, name_);
  EXPECT_EQ(p.PROC_ndm, 1u);
  EXPECT_EQ(p.PROC_nact, 3u);
  EXPECT_EQ(canhil_pman_get_counters(m).deadline_misses, 1u);
  EXPECT_EQ(canhil_pman_close(m), 0);
}

TEST_F(Pman, TwoMastersInOneProcessEachTickTheirOwnClient) {
  const std::string name2 = "agent" + std::to_string(agent_ + 1);
  canhil_pman* m1 = open(agent_);
  canhil_pman* m2 = open(agent_ + 1);
  ASSERT_EQ(canhil_pman_procadd(m1, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_procadd(m2, name2.c_str(), 1, 0, 10000), 0);
  Client c1({name_, agent_});
  Client c2({name2, agent_ + 1});
  ASSERT_EQ(canhil_pman_start(m1), 0);
  ASSERT_EQ(canhil_pman_start(m2), 0);
  ASSERT_EQ(c1.next(), 'A');
  ASSERT_EQ(c2.next(), 'A');
  for (int k = 0; k < 5; ++k) {
    ASSERT_EQ(canhil_pman_tick(m2), 1);
    ASSERT_EQ(c2.next(), 'C');
    if (k < 3) {
      ASSERT_EQ(canhil_pman_tick(m1), 1);
      ASSERT_EQ(c1.next(), 'C');
    }
  }
  EXPECT_EQ(c1.next(50), 0);
  EXPECT_EQ(query(m1, name_).PROC_nact, 3u);
  EXPECT_EQ(query(m2, name2).PROC_nact, 5u);
  EXPECT_EQ(canhil_pman_query(m1, name2.c_str(), nullptr), -1);
  PROC_TYPE other{};
  EXPECT_EQ(canhil_pman_query(m1, name2.c_str(), &other), -2) << "each master has its own table";
  EXPECT_EQ(canhil_pman_close(m1), 0);
  EXPECT_EQ(c1.next(), 'I');
  EXPECT_EQ(canhil_pman_close(m2), 0);
  EXPECT_EQ(c2.next(), 'I');
}

int g_qos_calls = 0;
int count_qos(int /*pindex*/) { return ++g_qos_calls; }

// CAMBADA's own master API: two tables switched with pman_save_ids and
// pman_switch_id, as CAMBADA's simulator does for its robots.
TEST_F(Pman, CambadaApiMastersSwitchedBySaveAndSwitch) {
  const std::string name2 = "agent" + std::to_string(agent_ + 1);
  g_qos_calls = 0;
  sched_param before{};
  const int policy = sched_getscheduler(0);
  sched_getparam(0, &before);
  void* qos = reinterpret_cast<void*>(&count_qos);
  const int r1 = PMAN_init2(agent_key(agent_), agent_key(agent_), qos, sizeof(int), PMAN_NEW);
  EXPECT_TRUE(r1 == 0 || r1 == -15) << r1;  // -15: no SCHED_FIFO (not root), the table works
  pman_save_ids(0);
  int prio = 50;
  ASSERT_EQ(PMAN_procadd(name_.c_str(), PMAN_NOPID, 1, 0, 10000, &prio, sizeof prio), 0);
  setenv("AGENT", std::to_string(agent_ + 1).c_str(), 1);
  const int r2 = PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, sizeof(int), PMAN_NEW);
  EXPECT_TRUE(r2 == 0 || r2 == -15) << r2;
  sched_setscheduler(0, policy, &before);  // as root the test process would now be SCHED_FIFO
  pman_save_ids(1);
  ASSERT_EQ(PMAN_procadd(name2.c_str(), PMAN_NOPID, 2, 0, 10000, nullptr, 0), 0);
  // Clients only now: CAMBADA's master publishes its table before registering
  // (a client in between gets -2); the handle API closes that gap.
  Client c1({name_, agent_});
  Client c2({name2, agent_ + 1});
  ASSERT_EQ(c1.next(), 'A');
  ASSERT_EQ(c2.next(), 'A');
  for (int k = 0; k < 4; ++k) {
    pman_switch_id(0);
    ASSERT_EQ(PMAN_tick(), 0);
    ASSERT_EQ(c1.next(), 'C');
    pman_switch_id(1);
    ASSERT_EQ(PMAN_tick(), 0);
    if (k % 2 == 0) {
      ASSERT_EQ(c2.next(), 'C');
    }
  }
  EXPECT_EQ(g_qos_calls, 1) << "master 0's QoS function, once: at its client's first activation";
  EXPECT_EQ(p_table->QoSupd, nullptr);
  PROC_TYPE p{};
  ASSERT_EQ(PMAN_query(&p, 1), 0);
  EXPECT_STREQ(p.PROC_name, name2.c_str());
  EXPECT_EQ(p.PROC_nact, 2u);
  EXPECT_EQ(PMAN_query(&p, 0), 1);
  EXPECT_EQ(PMAN_close(PMAN_CLFREE), 0);
  EXPECT_EQ(c2.next(), 'I');
  pman_switch_id(0);
  EXPECT_EQ(PMAN_close(PMAN_CLFREE), 0);
  EXPECT_EQ(c1.next(), 'I');
  pman_switch_id(1);
  EXPECT_EQ(p_table, nullptr) << "a closed master is forgotten by pman_switch_id";
}

TEST_F(Pman, PredecessorsEpilogueReleasesItsSuccessor) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, "vision", 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_procadd(m, name_.c_str(), 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  ASSERT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH), 0);
  EXPECT_EQ(PMAN_prec_add("vision", name_.c_str()), 0);
  EXPECT_EQ(PMAN_prec_add("nobody", name_.c_str()), -2);
  EXPECT_EQ(PMAN_prec_add("vision", "nobody"), -3);
  EXPECT_EQ(PMAN_close(PMAN_CLLEAVE), 0);
  Client pred({"vision", agent_});
  Client succ({name_, agent_});
  ASSERT_EQ(pred.next(), 'A');
  ASSERT_EQ(succ.next(), 'A');
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(canhil_pman_tick(m), 1) << "only the predecessor: the successor is pending";
    ASSERT_EQ(pred.next(), 'C');
    ASSERT_EQ(succ.next(), 'C') << "released by the predecessor's epilogue";
  }
  EXPECT_EQ(query(m, name_).PROC_nact, 3u);
  EXPECT_EQ(canhil_pman_close(m), 0);
}

// Any process can write the table (mode 0666): garbage must never crash the
// master, make it signal a process group or itself, or read out of bounds.
TEST_F(Pman, GarbledTableNeverCrashesTheMaster) {
  canhil_pman* m = open(agent_);
  ASSERT_EQ(canhil_pman_procadd(m, "ok", 1, 0, 10000), 0);
  ASSERT_EQ(canhil_pman_start(m), 0);
  auto* t = static_cast<PROC_TABLE_TYPE*>(shmat(shmget(agent_key(agent_), 0, 0), nullptr, 0));
  ASSERT_NE(reinterpret_cast<intptr_t>(t), -1);
  t->nprocs = 12345;
  t->ticks = INT_MAX;
  t->evt_lastindex = 999999;
  t->evt_firstindex = -3;
  std::memset(t->proc[1].PROC_name, 'A', sizeof t->proc[1].PROC_name);  // no NUL
  t->proc[1].PROC_id = -999999;                                         // a process group
  t->proc[1].PROC_period = 1;
  std::strcpy(t->proc[2].PROC_name, "zero");
  t->proc[2].PROC_id = getpid();
  t->proc[2].PROC_period = 0;
  std::strcpy(t->proc[3].PROC_name, "minus");
  t->proc[3].PROC_id = getpid();
  t->proc[3].PROC_period = -1;
  t->proc[3].PROC_phase = INT_MIN;
  t->proc[0].PROC_succ_index[0] = 1000;
  t->proc[0].PROC_succ_index[1] = -7;
  t->proc[0].PROC_qosdata = -5;
  for (int k = 0; k < 3; ++k) EXPECT_GE(canhil_pman_tick(m), 0);
  EXPECT_GT(canhil_pman_get_counters(m).bad_entries, 0u);
  EXPECT_EQ(canhil_pman_query(m, std::string(sizeof t->proc[1].PROC_name, 'A').c_str(), nullptr), -1);
  PROC_TYPE p{};
  EXPECT_EQ(canhil_pman_query(m, std::string(PNAME_LEN, 'A').c_str(), &p), -2);
  EXPECT_EQ(canhil_pman_procadd(m, "new", 1, 0, 0), 0);
  EXPECT_EQ(t->nprocs, 5) << "repaired";
  ASSERT_EQ(PMAN_init(SHMEM_OCAM_PMAN_KEY, SEM_OCAM_PMAN_KEY, nullptr, 0, PMAN_ATTACH), 0);
  EXPECT_EQ(PMAN_attach("ok", getpid()), 0);
  EXPECT_EQ(PMAN_epilogue("ok"), 0) << "its successor indexes are garbage";
  EXPECT_EQ(PMAN_QoSupd("ok", &p, sizeof p, PMAN_UPD_IMEDIATE), 0) << "its QoS offset is garbage";
  int names = 0;
  for (int r = PMAN_query(&p, 1); r == 0; r = PMAN_query(&p, 0), ++names) {
    EXPECT_LE(std::strlen(p.PROC_name), static_cast<size_t>(PNAME_LEN));
  }
  EXPECT_EQ(names, 5);
  testing::internal::CaptureStdout();
  EXPECT_EQ(PMAN_print(), 0);
  EXPECT_EQ(PMAN_print_prec(), 0);
  EXPECT_NE(testing::internal::GetCapturedStdout().find("minus"), std::string::npos);
  EXPECT_EQ(PMAN_deattach("ok"), 0);
  EXPECT_EQ(PMAN_close(PMAN_CLLEAVE), 0);
  shmdt(t);
  EXPECT_EQ(canhil_pman_close(m), 0) << "no SIGINT to itself or to a process group";
}

}  // namespace
