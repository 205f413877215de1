// The second team's set of databases (CAMBADA's DB_init_all(1)): both teams
// use agent numbers 1..6 and never see each other's items; a second-team
// process joins with SECOND_RTDB=1 or with RTDB_KEY 64 higher (the same
// keys); its frame wake-up is its own; a Database opened on set 1 reaches it.
#include <gtest/gtest.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <thread>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"
#include "support/rtdb_ipc.hpp"

namespace {

constexpr int kStride = 64;  // the second set's keys: the first's plus this

class SecondSet : public ::testing::Test {
 protected:
  void SetUp() override {
    setenv("AGENT", "1", 1);
    unsetenv("SECOND_RTDB");
  }
  void TearDown() override {
    unsetenv("SECOND_RTDB");
    EXPECT_EQ(keys_.leftovers(), "") << "segments left behind";
  }
  int key(int set, int agent) const { return keys_.canhil_base() + set * kStride + agent; }
  canhil::test::RtdbKeys keys_;
};

TEST_F(SecondSet, BothTeamsUseAgentOneAndKeepTheirItemsApart) {
  ASSERT_EQ(DB_init_all(0), 0);
  ASSERT_EQ(DB_init_all(1), 0);
  EXPECT_GE(shmget(key(0, CAMBADA_1), 0, 0), 0);
  EXPECT_GE(shmget(key(1, CAMBADA_1), 0, 0), 0) << "the second set is 64 keys higher";
  CMD_Vel first{1, 0, 0, false};
  CMD_Vel second{2, 0, 0, false};
  ASSERT_EQ(DB_put_in(CAMBADA_1, CAMBADA_1, CMD_VEL, &first, 0), static_cast<int>(sizeof first));
  ASSERT_EQ(DB_put_in(N_AGENTS + CAMBADA_1, CAMBADA_1, CMD_VEL, &second, 0), static_cast<int>(sizeof second));
  CMD_Vel out{};
  ASSERT_GE(DB_get_from(CAMBADA_1, CAMBADA_1, CMD_VEL, &out), 0);
  EXPECT_EQ(out.vx, 1.0f);
  ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_1, SELF, CMD_VEL, &out), 0);
  EXPECT_EQ(out.vx, 2.0f) << "SELF in the second set is that set's agent";
  // A shared item written in one team's robot reaches nobody in the other.
  RobotWS w{1, 2, 3, 1, 42};
  ASSERT_GT(DB_put_in(N_AGENTS + CAMBADA_2, CAMBADA_1, ROBOT_WS, &w, 0), 0);
  RobotWS seen{};
  ASSERT_GE(DB_get_from(CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen), 0);
  EXPECT_EQ(seen.frame, 0u);
  ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen), 0);
  EXPECT_EQ(seen.frame, 42u);
  EXPECT_EQ(DB_put_in(2 * N_AGENTS, CAMBADA_1, CMD_VEL, &first, 0), -1) << "no third set";
  EXPECT_EQ(DB_put_in(N_AGENTS + CAMBADA_1, N_AGENTS + CAMBADA_1, CMD_VEL, &first, 0), -1)
      << "the owner is an agent of the set, not a memory space";
  DB_free_all(1);
  EXPECT_LT(shmget(key(1, CAMBADA_1), 0, 0), 0) << "freed on its own";
  EXPECT_GE(shmget(key(0, CAMBADA_1), 0, 0), 0) << "the first set stays";
  EXPECT_EQ(DB_put_in(N_AGENTS + CAMBADA_1, CAMBADA_1, CMD_VEL, &second, 0), -1);
  DB_free_all(0);
}

TEST_F(SecondSet, AnAgentProcessJoinsWithSecondRtdbOrWithTheKeySixtyFourHigher) {
  ASSERT_EQ(DB_init_all(1), 0);
  for (const bool by_key : {false, true}) {
    const pid_t child = fork();
    if (child == 0) {
      if (by_key) {
        setenv("RTDB_KEY", std::to_string(keys_.canhil_base() + kStride).c_str(), 1);
      } else {
        setenv("SECOND_RTDB", "1", 1);
      }
      setenv("AGENT", "2", 1);
      if (DB_init() != 0) _exit(10);
      if (Whoami() != CAMBADA_2) _exit(11);  // the agent number, in either set
      CMD_Vel v{by_key ? 7.0f : 5.0f, 0, 0, false};
      if (DB_put(CMD_VEL, &v) != static_cast<int>(sizeof v)) _exit(12);
      DB_free();
      _exit(0);
    }
    int status = 0;
    waitpid(child, &status, 0);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child exit " << WEXITSTATUS(status);
    CMD_Vel out{};
    ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_2, CAMBADA_2, CMD_VEL, &out), 0);
    EXPECT_EQ(out.vx, by_key ? 7.0f : 5.0f);
  }
  DB_free_all(1);
}

TEST_F(SecondSet, TheFrameWakeUpReachesOnlyThatTeamsAgent) {
  ASSERT_EQ(DB_init_all(0), 0);
  setenv("SECOND_RTDB", "1", 1);
  ASSERT_EQ(DB_init(), 0);  // this thread is agent 1 of the second team
  EXPECT_EQ(Whoami(), CAMBADA_1);
  EXPECT_EQ(DB_signal_frame(CAMBADA_1), 0) << "the first team's agent 1";
  EXPECT_EQ(DB_wait_frame(20), 1) << "not ours: timeout";
  EXPECT_EQ(DB_signal_frame(N_AGENTS + CAMBADA_1), 0);
  EXPECT_EQ(DB_wait_frame(1000), 0);
  EXPECT_EQ(DB_signal_frame(2 * N_AGENTS), -1);
  CMD_Vel v{3, 0, 0, false};
  ASSERT_EQ(DB_put(CMD_VEL, &v), static_cast<int>(sizeof v));
  CMD_Vel out{};
  ASSERT_GE(DB_get_from(CAMBADA_1, CAMBADA_1, CMD_VEL, &out), 0);
  EXPECT_EQ(out.vx, 0.0f) << "DB_put went to the second set";
  DB_free();
  // The first team's agent 1 still has a post waiting: drain it the way its agent would.
  unsetenv("SECOND_RTDB");
  ASSERT_EQ(DB_init(), 0);
  EXPECT_EQ(DB_wait_frame(1000), 0);
  DB_free();
  DB_free_all(0);
}

TEST_F(SecondSet, ADatabaseOnSetOneSpeaksInTheTeamsAgentNumbers) {
  using canhil::rtdb::Scope;
  const auto first = canhil::rtdb::open_builtin(Scope::kAllAgents, 0);
  const auto second = canhil::rtdb::open_builtin(Scope::kAllAgents, 1);
  EXPECT_EQ(second->spaces(), first->spaces()) << "agents 0..N-1 in both";
  CMD_Pos p{4, 5, 6, 0, 0, 0};
  second->put(CAMBADA_3, CAMBADA_3, CMD_POS, std::as_bytes(std::span(&p, 1)));
  CMD_Pos out{};
  ASSERT_GE(DB_get_from(N_AGENTS + CAMBADA_3, CAMBADA_3, CMD_POS, &out), 0);
  EXPECT_EQ(out.px, 4.0f);
  ASSERT_TRUE(first->get(CAMBADA_3, CAMBADA_3, CMD_POS, std::as_writable_bytes(std::span(&out, 1))));
  EXPECT_EQ(out.px, 0.0f) << "the first team's robot 3 never had it";
  EXPECT_THROW(canhil::rtdb::open_builtin(Scope::kAllAgents, 2), canhil::SetupError);
}

}  // namespace
