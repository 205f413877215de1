// The RTDB C API: agents kept apart (in one process and in two), shared items
// reaching the others through the replicator, no torn values, ages, bad
// input, crashed runs reclaimed, owner-only segments removed on exit; CAMBADA's
// semantics (sizes returned, SELF, DB_comm_put / DB_comm_ini, nested inits,
// an rtdb.ini named by DB_set_config_file).
#include "canhil/rtdb/rtdb.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/ipc.h>
#include <sys/shm.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/replicator.hpp"
#include "rtdb_user.h"
#include "support/rtdb_ipc.hpp"

namespace {

using namespace std::chrono_literals;

// canhil's item layouts are fixed (the vision emulator and the agent share them).
static_assert(sizeof(canhil_vec2) == 8);
static_assert(sizeof(VisionInfo) == 4852);
static_assert(offsetof(VisionInfo, linePoints) == 2404);
static_assert(offsetof(VisionInfo, ball) == 4808);
static_assert(offsetof(VisionInfo, nBalls) == 4848);

// Every test gets its own System V keys, so runs never meet.
class Rtdb : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    key_ = 0x5A000000 + ((getpid() & 0xFFF) << 12) + ((++counter & 0x1F) << 7);  // 64 keys a set, two sets
    setenv("RTDB_KEY", std::to_string(key_).c_str(), 1);
    setenv("AGENT", "1", 1);
  }
  void TearDown() override {
    DB_free_all(0);
    DB_free();
    for (int a = 0; a < N_AGENTS; ++a) {  // nothing may be left behind
      EXPECT_LT(shmget(key_ + a, 0, 0), 0) << "agent " << a << "'s segment was not removed";
    }
  }
  int key_ = 0;
};

TEST_F(Rtdb, ConfigurationIsTheShippedOne) {
  EXPECT_EQ(DB_agent_count(), N_AGENTS);
  EXPECT_EQ(DB_item_count(), N_ITEMS);
  EXPECT_STREQ(DB_agent_name(CAMBADA_1), "CAMBADA_1");
  EXPECT_STREQ(DB_item_name(CMD_VEL), "CMD_VEL");
  EXPECT_EQ(DB_item_size(VISION_INFO), static_cast<int>(sizeof(VisionInfo)));
  EXPECT_EQ(DB_item_shared(CAMBADA_1, ROBOT_WS), 1);
  EXPECT_EQ(DB_item_shared(CAMBADA_1, CMD_VEL), 0);
  EXPECT_EQ(DB_item_shared(BASE_STATION, CMD_VEL), -1);
  EXPECT_EQ(DB_item_name(N_ITEMS), nullptr);
}

TEST_F(Rtdb, PutGetRoundTripWithAge) {
  ASSERT_EQ(DB_init(), 0);
  EXPECT_EQ(Whoami(), 1);
  CMD_Vel v{0.5f, -0.25f, 1.5f, true};
  ASSERT_EQ(DB_put(CMD_VEL, &v), static_cast<int>(sizeof v)) << "the item's size, as CAMBADA's library";
  CMD_Vel back{};
  const int age = DB_get(CAMBADA_1, CMD_VEL, &back);
  EXPECT_GE(age, 0);
  EXPECT_LT(age, 1000);
  EXPECT_EQ(std::memcmp(&v, &back, sizeof v), 0);
}

TEST_F(Rtdb, AgesFollowTheClockTheProcessSetsAndTheMonotonicOneAgain) {
  ASSERT_EQ(DB_init(), 0);
  CMD_Vel v{0.5f, -0.25f, 1.5f, true};
  ASSERT_GT(DB_put(CMD_VEL, &v), 0);        // stamped by the monotonic clock
  std::int64_t virtual_ns = 5'000'000'000;  // any start: it is taken to be now
  DB_set_clock([](void* t) { return *static_cast<std::int64_t*>(t); }, &virtual_ns);
  CMD_Vel back{};
  EXPECT_LT(DB_get(CAMBADA_1, CMD_VEL, &back), 1000) << "a stamp from before compares with the new clock";
  virtual_ns += 7'300'000'000;  // 7.3 s later in virtual time, at once in real time
  EXPECT_EQ(DB_get(CAMBADA_1, CMD_VEL, &back), 7300);
  ASSERT_GT(DB_put(CMD_VEL, &v), 0);
  virtual_ns += 250'000'000;
  EXPECT_EQ(DB_get(CAMBADA_1, CMD_VEL, &back), 250);
  DB_set_clock(nullptr, nullptr);
  EXPECT_EQ(DB_get(CAMBADA_1, CMD_VEL, &back), 0) << "stamped ahead of the monotonic clock: fresh";
}

TEST_F(Rtdb, APartOfAnItemIsThoseBytesOfIt) {
  ASSERT_EQ(DB_init(), 0);
  VisionInfo v{};
  for (int i = 0; i < MAX_POINTS; ++i) v.linePoints.point[i] = {static_cast<float>(i), -static_cast<float>(i)};
  v.linePoints.nPoints = 7;
  v.ball[0] = {1.25f, -2.5f};
  v.nBalls = 1;
  ASSERT_GT(DB_put(VISION_INFO, &v), 0);
  // The ball and its count, at the item's end: two words, the first in part.
  struct {
    canhil_vec2 ball[MAX_BALLS];
    int nBalls;
  } tail{};
  EXPECT_GE(DB_get_part(DB_space(), CAMBADA_1, VISION_INFO, offsetof(VisionInfo, ball), sizeof tail, &tail), 0);
  EXPECT_EQ(tail.ball[0].x, 1.25f);
  EXPECT_EQ(tail.ball[0].y, -2.5f);
  EXPECT_EQ(tail.nBalls, 1);
  // Every offset and length of a span in the middle, against the whole item.
  VisionInfo whole{};
  ASSERT_GE(DB_get(CAMBADA_1, VISION_INFO, &whole), 0);
  const auto* bytes = reinterpret_cast<const unsigned char*>(&whole);
  unsigned char part[24];
  for (std::size_t offset = 2400; offset < 2420; ++offset) {
    for (std::size_t size = 0; size <= sizeof part; ++size) {
      ASSERT_GE(DB_get_part(DB_space(), SELF, VISION_INFO, offset, size, part), 0) << offset << " " << size;
      EXPECT_EQ(std::memcmp(part, bytes + offset, size), 0) << offset << " " << size;
    }
  }
  EXPECT_EQ(DB_get_part(DB_space(), SELF, VISION_INFO, sizeof(VisionInfo) - 4, 8, part), -1) << "past the end";
  EXPECT_EQ(DB_get_part(DB_space(), SELF, VISION_INFO, sizeof(VisionInfo) + 1, 0, part), -1);
  EXPECT_EQ(DB_get_part(DB_space(), SELF, N_ITEMS, 0, 4, part), -1) << "no such item";
}

TEST_F(Rtdb, PuttingRangesWritesThoseBytesOfTheImageAndStampsTheItem) {
  ASSERT_EQ(DB_init(), 0);
  VisionInfo before{};
  for (int i = 0; i < MAX_POINTS; ++i) before.obstacles.point[i] = {static_cast<float>(i), 1.0f};
  before.obstacles.nPoints = MAX_POINTS;
  ASSERT_GT(DB_put(VISION_INFO, &before), 0);
  // A new image that differs everywhere; only the ranges may reach the slot.
  VisionInfo image{};
  auto* raw = reinterpret_cast<unsigned char*>(&image);
  for (std::size_t i = 0; i < sizeof image; ++i) raw[i] = static_cast<unsigned char>(i * 7 + 3);
  std::mt19937 pick(11);
  for (int round = 0; round < 50; ++round) {
    ASSERT_GT(DB_put(VISION_INFO, &before), 0);
    std::vector<std::size_t> ranges;  // offset, length, offset, length, ...
    std::vector<bool> inside(sizeof image, false);
    const int n = static_cast<int>(pick() % 4);
    for (int k = 0; k < n; ++k) {
      const std::size_t offset = pick() % sizeof image;
      const std::size_t size = pick() % std::min<std::size_t>(64, sizeof image - offset + 1);
      ranges.push_back(offset);
      ranges.push_back(size);
      for (std::size_t b = offset; b < offset + size; ++b) inside[b] = true;
    }
    ASSERT_EQ(DB_put_ranges(DB_space(), SELF, VISION_INFO, &image, ranges.data(), n, 0),
              static_cast<int>(sizeof image));
    VisionInfo got{};
    ASSERT_GE(DB_get(CAMBADA_1, VISION_INFO, &got), 0);
    const auto* g = reinterpret_cast<const unsigned char*>(&got);
    const auto* b = reinterpret_cast<const unsigned char*>(&before);
    for (std::size_t i = 0; i < sizeof image; ++i) {
      // A range's whole words are copied: a byte beside one, in its word, may come from the image too.
      if (inside[i]) {
        ASSERT_EQ(g[i], raw[i]) << "round " << round << ", byte " << i;
      }
      const std::size_t word = i - i % 8;
      bool near = false;
      for (std::size_t w = word; w < word + 8 && w < sizeof image; ++w) near = near || inside[w];
      if (!near) {
        ASSERT_EQ(g[i], b[i]) << "round " << round << ", byte " << i << " is outside every range";
      }
    }
  }
  const std::size_t past[2] = {sizeof(VisionInfo) - 4, 8};
  EXPECT_EQ(DB_put_ranges(DB_space(), SELF, VISION_INFO, &image, past, 1, 0), -1) << "past the end";
  EXPECT_EQ(DB_put_ranges(DB_space(), SELF, VISION_INFO, &image, nullptr, -1, 0), -1);
  EXPECT_EQ(DB_put_ranges(DB_space(), SELF, VISION_INFO, &image, nullptr, 0, -1), -1) << "a negative life";
  EXPECT_EQ(DB_put_ranges(DB_space(), SELF, N_ITEMS, &image, nullptr, 0, 0), -1) << "no such item";
  // Aged as DB_put_in ages: life 40 ms.
  EXPECT_EQ(DB_put_ranges(DB_space(), SELF, VISION_INFO, &image, nullptr, 0, 40), static_cast<int>(sizeof image));
  VisionInfo got{};
  const int age = DB_get(CAMBADA_1, VISION_INFO, &got);
  EXPECT_GE(age, 40);
  EXPECT_LT(age, 1040);
}

TEST_F(Rtdb, BadIdsAndAgentsAreErrors) {
  CMD_Vel v{};
  EXPECT_EQ(DB_put(CMD_VEL, &v), -1) << "before DB_init";
  EXPECT_EQ(DB_get(1, CMD_VEL, &v), -1);
  EXPECT_EQ(Whoami(), -1);
  ASSERT_EQ(DB_init(), 0);
  EXPECT_EQ(DB_put(N_ITEMS, &v), -1);
  EXPECT_EQ(DB_put(-1, &v), -1);
  EXPECT_EQ(DB_put(COACH_INFO, &v), -1) << "not in a player's schema";
  EXPECT_EQ(DB_get(N_AGENTS, CMD_VEL, &v), -1);
  EXPECT_EQ(DB_get(CAMBADA_2, CMD_VEL, &v), -1) << "another robot's local item is not here";
  EXPECT_EQ(DB_put(CMD_VEL, nullptr), -1);
}

TEST_F(Rtdb, AgentEnvironmentIsChecked) {
  unsetenv("AGENT");
  testing::internal::CaptureStderr();
  EXPECT_EQ(DB_init(), -1);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("AGENT is not set"), std::string::npos);
  setenv("AGENT", "99", 1);
  testing::internal::CaptureStderr();
  EXPECT_EQ(DB_init(), -1);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("use 0 to 6"), std::string::npos);
}

TEST_F(Rtdb, NeverWrittenItemsReadAsZerosAndLifeAgesAWrite) {
  ASSERT_EQ(DB_init_all(0), 0);
  CMD_Pos p{1, 2, 3, 4, 5, 6};
  ASSERT_GE(DB_get_from(CAMBADA_2, CAMBADA_2, CMD_POS, &p), 0);
  EXPECT_EQ(p.px, 0.0f);
  CMD_Pos q{1, 2, 3, 0, 0, 0};
  ASSERT_EQ(DB_put_in(CAMBADA_2, CAMBADA_2, CMD_POS, &q, 250), static_cast<int>(sizeof q));
  const int age = DB_get_from(CAMBADA_2, CAMBADA_2, CMD_POS, &p);
  EXPECT_GE(age, 250);
  EXPECT_LT(age, 1250);
  EXPECT_EQ(p.py, 2.0f);
  EXPECT_EQ(DB_put_in(CAMBADA_2, CAMBADA_2, CMD_POS, &q, -5), -1);
}

TEST_F(Rtdb, TwoAgentsInOneProcessKeepLocalItemsApartAndShareThroughTheReplicator) {
  ASSERT_EQ(DB_init_all(0), 0);
  CMD_Vel v1{1, 1, 1, false};
  CMD_Vel v2{2, 2, 2, false};
  ASSERT_EQ(DB_put_in(CAMBADA_1, CAMBADA_1, CMD_VEL, &v1, 0), static_cast<int>(sizeof v1));
  ASSERT_EQ(DB_put_in(CAMBADA_2, CAMBADA_2, CMD_VEL, &v2, 0), static_cast<int>(sizeof v2));
  CMD_Vel out{};
  DB_get_from(CAMBADA_1, CAMBADA_1, CMD_VEL, &out);
  EXPECT_EQ(out.vx, 1.0f);
  DB_get_from(CAMBADA_2, CAMBADA_2, CMD_VEL, &out);
  EXPECT_EQ(out.vx, 2.0f);
  EXPECT_EQ(DB_get_from(CAMBADA_2, CAMBADA_1, CMD_VEL, &out), -1) << "local items are not visible to others";

  RobotWS w{3.0f, 4.0f, 0.5f, 1, 7};
  ASSERT_EQ(DB_put_in(CAMBADA_1, CAMBADA_1, ROBOT_WS, &w, 0), static_cast<int>(sizeof w));
  RobotWS seen{};
  DB_get_from(CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 0u) << "not replicated yet";
  const auto db = canhil::rtdb::open_builtin(canhil::rtdb::Scope::kAllAgents);
  canhil::rtdb::Replicator rep(*db, {});
  rep.cycle(0ns);
  DB_get_from(CAMBADA_2, CAMBADA_1, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 7u);
  EXPECT_EQ(seen.x, 3.0f);
  DB_get_from(BASE_STATION, CAMBADA_1, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 7u) << "the base station gets it too";
  // Every cycle copies every shared item (the base station's COACH_INFO and
  // the six robots' ROBOT_WS) to the six other agents.
  EXPECT_EQ(rep.stats().copied, 7u * (N_AGENTS - 1));
}

TEST_F(Rtdb, TwoAgentsInTwoProcesses) {
  // One pipe each way: the child says "written", the parent says "done".
  int to_parent[2];
  int to_child[2];
  ASSERT_EQ(pipe(to_parent), 0);
  ASSERT_EQ(pipe(to_child), 0);
  const pid_t child = fork();
  if (child == 0) {
    setenv("AGENT", "1", 1);
    if (DB_init() != 0) _exit(10);
    CMD_Vel v{1.5f, 0, 0, false};
    RobotWS w{0, 0, 0, 1, 99};
    DB_put(CMD_VEL, &v);
    DB_put(ROBOT_WS, &w);
    (void)!write(to_parent[1], "x", 1);
    char c;
    (void)!read(to_child[0], &c, 1);  // wait until the parent is done
    DB_free();
    _exit(0);
  }
  char c;
  ASSERT_EQ(read(to_parent[0], &c, 1), 1);
  setenv("AGENT", "2", 1);
  ASSERT_EQ(DB_init(), 0);
  CMD_Vel mine{2.5f, 0, 0, false};
  ASSERT_EQ(DB_put(CMD_VEL, &mine), static_cast<int>(sizeof mine));
  CMD_Vel out{};
  DB_get(CAMBADA_2, CMD_VEL, &out);
  EXPECT_EQ(out.vx, 2.5f) << "its own item, not the other process's";
  EXPECT_EQ(DB_get(CAMBADA_1, CMD_VEL, &out), -1);
  // The replicator (here in this process) carries the shared item across.
  const auto db = canhil::rtdb::open_builtin(canhil::rtdb::Scope::kAllAgents);
  canhil::rtdb::Replicator rep(*db, {});
  rep.cycle(0ns);
  RobotWS seen{};
  DB_get(CAMBADA_1, ROBOT_WS, &seen);
  EXPECT_EQ(seen.frame, 99u);
  (void)!write(to_child[1], "x", 1);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  for (int fd : {to_parent[0], to_parent[1], to_child[0], to_child[1]}) close(fd);
}

TEST_F(Rtdb, NoReaderEverSeesAHalfWrittenItem) {
  ASSERT_EQ(DB_init(), 0);
  std::atomic<bool> stop{false};
  std::atomic<long> torn{0};
  std::atomic<long> reads{0};
  std::thread reader([&] {
    VisionInfo v;  // 4.8 kB: a copy takes long enough to be caught mid-write
    while (!stop) {
      DB_get(CAMBADA_1, VISION_INFO, &v);
      const int k = v.nBalls;
      for (int i = 0; i < MAX_POINTS; ++i) {
        if (v.linePoints.point[i].x != static_cast<float>(k) || v.obstacles.point[i].y != static_cast<float>(k)) {
          ++torn;
          break;
        }
      }
      ++reads;
    }
  });
  auto v = std::make_unique<VisionInfo>();
  // Write until the reader has read often enough while writes were going on
  // (on a busy machine the reader thread may start late), within a bound.
  constexpr int kMostWrites = 20'000'000;
  for (int k = 0; (k < 200000 || reads < 2000) && k < kMostWrites && torn == 0; ++k) {
    v->nBalls = k;
    for (int i = 0; i < MAX_POINTS; ++i) {
      v->linePoints.point[i] = {static_cast<float>(k), static_cast<float>(k)};
      v->obstacles.point[i] = {static_cast<float>(k), static_cast<float>(k)};
    }
    DB_put(VISION_INFO, v.get());
  }
  stop = true;
  reader.join();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_GE(reads.load(), 2000) << "the reader hardly ran while the writer wrote";
}

TEST_F(Rtdb, SelfMeansTheAgentWhoseDatabaseIsRead) {
  ASSERT_EQ(DB_init(), 0);
  CMD_Vel v{0.75f, 0, 0, false};
  ASSERT_EQ(DB_put(CMD_VEL, &v), static_cast<int>(sizeof v));
  CMD_Vel back{};
  EXPECT_GE(DB_get(SELF, CMD_VEL, &back), 0);
  EXPECT_EQ(back.vx, 0.75f);
  ASSERT_EQ(DB_init_all(0), 0);
  CMD_Vel two{2.25f, 0, 0, false};
  ASSERT_EQ(DB_put_in(CAMBADA_2, SELF, CMD_VEL, &two, 0), static_cast<int>(sizeof two));
  EXPECT_GE(DB_get_from(CAMBADA_2, SELF, CMD_VEL, &back), 0);
  EXPECT_EQ(back.vx, 2.25f) << "agent 2's own item, in agent 2's database";
}

TEST_F(Rtdb, InitCallsNestAndEachModeIsFreedOnItsOwn) {
  ASSERT_EQ(DB_init(), 0);
  ASSERT_EQ(DB_init(), 0);
  DB_free();
  CMD_Vel v{};
  EXPECT_GT(DB_put(CMD_VEL, &v), 0) << "one DB_init still open";
  ASSERT_EQ(DB_init_all(0), 0);
  ASSERT_EQ(DB_init_all(0), 0);
  DB_free_all(0);
  EXPECT_GT(DB_put_in(CAMBADA_3, CAMBADA_3, CMD_VEL, &v, 0), 0) << "one DB_init_all still open";
  DB_free_all(0);
  EXPECT_EQ(DB_put_in(CAMBADA_3, CAMBADA_3, CMD_VEL, &v, 0), -1);
  EXPECT_LT(shmget(key_ + CAMBADA_3, 0, 0), 0) << "agent 3's database went with the last DB_free_all";
  EXPECT_GT(DB_put(CMD_VEL, &v), 0) << "DB_free_all leaves DB_init's agent attached";
  DB_free();
  EXPECT_EQ(DB_put(CMD_VEL, &v), -1);
}

TEST_F(Rtdb, CommPutStoresAnotherAgentsSharedItemOnly) {
  RobotWS w{1, 2, 3, 1, 5};
  EXPECT_EQ(DB_comm_put(CAMBADA_2, ROBOT_WS, sizeof w, &w, 0), -1) << "before DB_init";
  ASSERT_EQ(DB_init(), 0);
  testing::internal::CaptureStderr();
  EXPECT_EQ(DB_comm_put(CAMBADA_1, ROBOT_WS, sizeof w, &w, 0), -1) << "this agent's own item";
  EXPECT_EQ(DB_comm_put(SELF, ROBOT_WS, sizeof w, &w, 0), -1);
  CMD_Vel v{};
  EXPECT_EQ(DB_comm_put(CAMBADA_2, CMD_VEL, sizeof v, &v, 0), -1) << "a local item";
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("this process's own"), std::string::npos) << said;
  EXPECT_NE(said.find("not a shared item of agent 2"), std::string::npos) << said;
  ASSERT_EQ(DB_comm_put(CAMBADA_2, ROBOT_WS, 0, &w, 300), static_cast<int>(sizeof w)) << "size is ignored";
  RobotWS seen{};
  EXPECT_GE(DB_get(CAMBADA_2, ROBOT_WS, &seen), 300);
  EXPECT_EQ(seen.frame, 5u);
}

TEST_F(Rtdb, CommIniListsThisAgentsSharedItems) {
  RTDBconf_var rec[MAX_RECS];
  EXPECT_EQ(DB_comm_ini(rec), -1) << "before DB_init";
  ASSERT_EQ(DB_init(), 0);
  ASSERT_EQ(DB_comm_ini(rec), 1);
  EXPECT_EQ(rec[0].id, ROBOT_WS);
  EXPECT_EQ(rec[0].size, static_cast<int>(sizeof(RobotWS)));
  EXPECT_EQ(rec[0].period, 1);
}

// The static library reads an rtdb.ini when the program names one, and goes
// back to its linked table when the program takes it back.
TEST_F(Rtdb, SetConfigFileSwitchesToAnIniBeforeInit) {
  const auto dir = canhil::test::scratch_dir("rtdb_set_config");
  canhil::test::write_file(dir / "rtdb.ini", "# 0 COACH\n1 40 1 s\n\n# 1 ROBOT\n0 24 1 s\n2 7 1 l\n");
  DB_set_config_file((dir / "rtdb.ini").c_str());
  ASSERT_EQ(DB_init(), 0);
  EXPECT_EQ(DB_agent_count(), 2);
  EXPECT_EQ(DB_item_count(), 3);
  EXPECT_STREQ(DB_agent_name(1), "ROBOT");
  EXPECT_STREQ(DB_item_name(2), "item2") << "an rtdb.ini has no item names";
  EXPECT_STREQ(DB_config_source(), (dir / "rtdb.ini").c_str());
  unsigned char seven[7] = {1, 2, 3, 4, 5, 6, 7};
  EXPECT_EQ(DB_put(2, seven), 7) << "the ini's size";
  testing::internal::CaptureStderr();
  DB_set_config_file(nullptr);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("changes once all is freed"), std::string::npos);
  EXPECT_EQ(DB_item_count(), 3) << "not while attached";
  DB_free();
  EXPECT_EQ(DB_item_count(), N_ITEMS) << "the linked table again";
  EXPECT_STREQ(DB_item_name(CMD_VEL), "CMD_VEL");
}

TEST_F(Rtdb, AnIniThatDoesNotParseFailsInitNamingFileAndLine) {
  const auto dir = canhil::test::scratch_dir("rtdb_bad_ini");
  canhil::test::write_file(dir / "rtdb.ini", "## a comment\n# 0 BASE\n1 40 1 s\n# 1 ROBOT\n0 24 1 x\n");
  DB_set_config_file((dir / "rtdb.ini").c_str());
  testing::internal::CaptureStderr();
  EXPECT_EQ(DB_init(), -1);
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find((dir / "rtdb.ini").string() + ":5: item 0 is \"x\"; write s (shared) or l (local)"),
            std::string::npos)
      << said;
  DB_set_config_file(nullptr);
  EXPECT_EQ(DB_item_count(), N_ITEMS);
}

TEST_F(Rtdb, SegmentsAreOwnerOnlyAndRemovedOnCleanExit) {
  ASSERT_EQ(DB_init(), 0);
  const int id = shmget(key_ + 1, 0, 0);
  ASSERT_GE(id, 0);
  shmid_ds ds{};
  ASSERT_EQ(shmctl(id, IPC_STAT, &ds), 0);
  EXPECT_EQ(ds.shm_perm.mode & 0777, 0600);
  DB_free();
  EXPECT_LT(shmget(key_ + 1, 0, 0), 0) << "the last process out removes the segment";
}

TEST_F(Rtdb, ACrashedRunsSegmentIsReclaimed) {
  const pid_t child = fork();
  if (child == 0) {
    if (DB_init() != 0) _exit(10);
    CMD_Vel v{9, 9, 9, true};
    DB_put(CMD_VEL, &v);
    kill(getpid(), SIGKILL);  // crash: no DB_free
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  ASSERT_GE(shmget(key_ + 1, 0, 0), 0) << "the crash left the segment behind";
  testing::internal::CaptureStderr();
  ASSERT_EQ(DB_init(), 0);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("reclaiming agent 1's database left by a crashed run"),
            std::string::npos);
  CMD_Vel v{};
  DB_get(CAMBADA_1, CMD_VEL, &v);
  EXPECT_EQ(v.vx, 0.0f) << "a fresh database, not the crashed run's values";
}

TEST_F(Rtdb, VisionWakesTheAgent) {
  ASSERT_EQ(DB_init(), 0);
  EXPECT_EQ(DB_wait_frame(20), 1) << "nothing posted: timeout";
  // Blocked in the wait, woken by a later frame.
  std::thread vision([] {
    std::this_thread::sleep_for(20ms);
    DB_signal_frame(CAMBADA_1);
  });
  EXPECT_EQ(DB_wait_frame(5000), 0);
  vision.join();
  // Two frames while the agent was busy wake it once.
  DB_signal_frame(CAMBADA_1);
  DB_signal_frame(CAMBADA_1);
  EXPECT_EQ(DB_wait_frame(20), 0);
  EXPECT_EQ(DB_wait_frame(20), 1);
}

TEST_F(Rtdb, AFrameSignalReachesAnAgentThatLeftAndCameBack) {
  // The signalling side keeps its semaphore open while it has the space; the
  // last one out of a space removes it, and a later agent gets a new one.
  ASSERT_EQ(DB_init(), 0);
  for (int i = 0; i < 3; ++i) DB_signal_frame(CAMBADA_1);
  EXPECT_EQ(DB_wait_frame(20), 0);
  EXPECT_EQ(DB_wait_frame(20), 1) << "three signals while busy wake once";
  DB_free();
  ASSERT_EQ(DB_init(), 0);
  DB_signal_frame(CAMBADA_1);
  EXPECT_EQ(DB_wait_frame(2000), 0) << "the new semaphore, not the one removed";
}

}  // namespace
