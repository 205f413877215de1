// The seam to the team's laptop software: what a run writes into and reads
// from the team's RTDB, in the team's layout, and how it wakes the team's
// agents. canhil's RTDB in canhil's layout; the stand-in team library
// (tests/support/team_rtdb/) with a CAMBADA-like table in CAMBADA's layout;
// tables that disagree with the layout. Each test runs in an IPC namespace of
// its own (PMan's keys are fixed by the agent number, 0x9011 + 2 x agent).
#include "canhil/emulator/laptop_link.hpp"

#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>
#include <fstream>
#include <random>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/rtdb.h"
#include "support/counter_watch.hpp"
#include "support/team_rtdb.hpp"
#include "support/test_paths.hpp"

namespace canhil::emulator {
namespace {

std::string cambada_like(const char* file) { return test::source_dir() + "/tests/support/cambada_like/" + file; }

class LaptopLinkTest : public test::WatchedTest {
 protected:
  void SetUp() override {
    ASSERT_EQ(unshare(CLONE_NEWIPC), 0) << "a private IPC namespace needs root (CAP_SYS_ADMIN): " << strerror(errno);
  }
  static LaptopSide team(bool realtime = false) {
    LaptopSide side;
    side.rtdb_lib = test::team_rtdb_library();
    side.rtdb_items = cambada_like("rtdb_user.h");
    side.rtdb_ini = cambada_like("config/rtdb.ini");
    return resolve_laptop(side, 1, realtime);
  }
  static CoachState coach(std::size_t robots) {
    CoachState c;
    c.players.resize(robots);
    return c;
  }
  static vision_emu::VisionFrame frame() {
    vision_emu::VisionFrame f;
    f.lines = {{1.0, 2.0}, {-0.5, 0.25}};
    f.balls = {{0.1, 1.5}};
    f.obstacles = {{2.0, -1.0}};
    return f;
  }
};

float f32_at(const std::vector<std::byte>& b, std::size_t offset) {
  float v = 0;
  std::memcpy(&v, b.data() + offset, sizeof v);
  return v;
}
std::int32_t i32_at(const std::vector<std::byte>& b, std::size_t offset) {
  std::int32_t v = 0;
  std::memcpy(&v, b.data() + offset, sizeof v);
  return v;
}

TEST_F(LaptopLinkTest, DefaultsFollowTheRtdbAndTheClock) {
  LaptopSide side = resolve_laptop({}, 1, false);
  EXPECT_EQ(side.rtdb_lib, "builtin");
  EXPECT_EQ(side.layout, "canhil");
  EXPECT_EQ(side.pman, "none") << "nothing outside the process follows virtual time";
  EXPECT_FALSE(*side.replicate);
  side = resolve_laptop({}, 3, true);
  EXPECT_EQ(side.pman, "builtin");
  EXPECT_TRUE(*side.replicate);
  EXPECT_EQ(team().layout, "cambada") << "a team library speaks CAMBADA's layout unless told";
  LaptopSide half;
  half.rtdb_lib = "/some/librtdb.so";
  EXPECT_THROW(resolve_laptop(half, 1, true), SetupError);
  LaptopSide stray;
  stray.rtdb_ini = "rtdb.ini";
  EXPECT_THROW(resolve_laptop(stray, 1, true), SetupError);
}

TEST_F(LaptopLinkTest, VisionAndCoachGoIntoTheTeamsLibraryInTheTeamsUnits) {
  LaptopLink link(team(), {1}, coach(1));
  rtdb::Database& db = link.database();
  EXPECT_EQ(db.library(), test::team_rtdb_library());
  const int vision = *db.items().id("VISION_INFO");
  const int coach_info = *db.items().id("COACH_INFO");
  const int before = test::standin_put_count(1, vision);
  link.vision_frame(0, frame());
  EXPECT_EQ(test::standin_put_count(1, vision), before + 1) << "written through the team's library";
  std::vector<std::byte> v(8052);
  ASSERT_TRUE(db.get(1, 1, vision, v));
  // CAMBADA's VisionInfo: line points from 4008 (their count at 4004) in
  // millimetres; obstacles (from 4) and the ball (from 8008) in metres.
  EXPECT_EQ(i32_at(v, 4004), 2);
  EXPECT_FLOAT_EQ(f32_at(v, 4), 2.0F);
  EXPECT_FLOAT_EQ(f32_at(v, 8012), 1.5F);
  EXPECT_EQ(i32_at(v, 8048), 1);
  EXPECT_FLOAT_EQ(f32_at(v, 4008), 1000.0F);
  EXPECT_FLOAT_EQ(f32_at(v, 4012), 2000.0F);
  EXPECT_FLOAT_EQ(f32_at(v, 4016), -500.0F);
  // The coach: the base station's shared copy in robot 1's database, and its own.
  std::vector<std::byte> c(260);
  ASSERT_TRUE(db.get(1, 0, coach_info, c));
  EXPECT_EQ(static_cast<int>(c[13]), 1) << "playerInfo[0].running";
  ASSERT_TRUE(db.get(1, 1, coach_info, c));
  EXPECT_EQ(static_cast<int>(c[13]), 1);
  CoachState stop = coach(1);
  stop.game_state = "stop";
  stop.players[0].running = false;
  link.write_coach(stop);
  ASSERT_TRUE(db.get(1, 0, coach_info, c));
  EXPECT_EQ(static_cast<int>(c[13]), 0) << "the coach stopped robot 1";
  EXPECT_EQ(link.vision_writes(), 1u);
  EXPECT_GE(link.coach_writes(), 2u);
}

TEST_F(LaptopLinkTest, CanhilsOwnRtdbInCanhilsLayoutAndThePoseReadBack) {
  setenv("RTDB_KEY", std::to_string(0x5F000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  LaptopLink link(resolve_laptop({}, 2, false), {1, 2}, coach(2));
  rtdb::Database& db = link.database();
  link.vision_frame(1, frame());
  std::vector<std::byte> v(4852);
  ASSERT_TRUE(db.get(2, 2, *db.items().id("VISION_INFO"), v));
  EXPECT_EQ(i32_at(v, 2404), 2) << "canhil's layout: line points in metres";
  EXPECT_FLOAT_EQ(f32_at(v, 2408), 1.0F);
  std::vector<std::byte> pos(24);
  const float stored[6] = {1.5F, -2.0F, 0.5F, 0, 0, 0};
  std::memcpy(pos.data(), stored, sizeof stored);
  db.put(2, 2, *db.items().id("CMD_POS"), pos);
  const auto p = link.reported_pose(1);
  ASSERT_TRUE(p.has_value());
  EXPECT_DOUBLE_EQ(p->x_m, 1.5);
  EXPECT_DOUBLE_EQ(p->heading_rad, 0.5);
  EXPECT_NE(link.replicator_stats(), nullptr) << "two robots: the replicator runs";
}

TEST_F(LaptopLinkTest, ARobotPlacedAsksItsHandlerThroughTheLayoutAndAClearedDatabaseHoldsZeros) {
  // The second team's set: the link finds the agent's database in it.
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  LaptopLink link(resolve_laptop({}, 2, false), {1, 2}, coach(2), 1);
  rtdb::Database& db = link.database();
  const int setpose = *db.items().id("CMD_SETPOSE");
  link.place(1, {1.25, -3.5, 0.75});
  std::vector<std::byte> b(16);
  ASSERT_TRUE(db.get(2, 2, setpose, b));
  EXPECT_FLOAT_EQ(f32_at(b, 0), 1.25F) << "canhil's layout: x, y, heading as floats";
  EXPECT_FLOAT_EQ(f32_at(b, 4), -3.5F);
  EXPECT_FLOAT_EQ(f32_at(b, 8), 0.75F);
  EXPECT_EQ(static_cast<int>(b[12]), 0) << "command: set the pose";
  EXPECT_EQ(static_cast<int>(b[13]), 1) << "pending";
  ASSERT_TRUE(db.get(1, 1, setpose, b));
  EXPECT_EQ(f32_at(b, 0), 0.0F) << "robot 0's agent was not asked";
  link.clear_items(1);
  ASSERT_TRUE(db.get(2, 2, setpose, b));
  EXPECT_EQ(static_cast<int>(b[13]), 0) << "cleared";
}

TEST_F(LaptopLinkTest, FramesPutInPartsLeaveVisionInfoAsWholeWritesWould) {
  // canhil's RTDB takes only the parts of VISION_INFO a frame changed; the
  // team's stand-in library (no DB_put_ranges) the whole item. Either way the
  // item must read as a fresh write of the frame, through lists that grow,
  // shrink and empty.
  setenv("RTDB_KEY", std::to_string(0x5E000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  for (const bool builtin : {true, false}) {
    LaptopLink link(builtin ? resolve_laptop({}, 1, false) : team(), {1}, coach(1));
    rtdb::Database& db = link.database();
    const int id = *db.items().id("VISION_INFO");
    const rtdb::ItemLayout& item = *link.layout().item("VISION_INFO");
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> metres(-8, 8);
    for (int n = 0; n < 40; ++n) {
      vision_emu::VisionFrame f;
      const std::size_t lines = n % 5 == 2 ? 0 : rng() % 320;
      for (std::size_t k = 0; k < lines; ++k) f.lines.emplace_back(metres(rng), metres(rng));
      for (std::size_t k = rng() % 40; k > 0; --k) f.obstacles.emplace_back(metres(rng), metres(rng));
      if (n % 3 == 0) f.balls.emplace_back(metres(rng), metres(rng));
      link.vision_frame(0, f);
      rtdb::ItemBuffer fresh(item);
      const auto as_points = [](const std::vector<Eigen::Vector2d>& v) {
        std::vector<std::array<double, 2>> out;
        out.reserve(v.size());
        for (const auto& p : v) out.push_back({p.x(), p.y()});
        return out;
      };
      fresh.set_points(fresh.quantity("obstacles"), as_points(f.obstacles));
      fresh.set_points(fresh.quantity("lines"), as_points(f.lines));
      fresh.set_points(fresh.quantity("balls"), as_points(f.balls));
      std::vector<std::byte> got(item.size_bytes());
      ASSERT_TRUE(db.get(1, 1, id, got));
      ASSERT_EQ(std::memcmp(got.data(), fresh.data(), got.size()), 0)
          << (builtin ? "canhil's RTDB" : "the team's library") << ", frame " << n << " (" << lines << " line points)";
    }
  }
}

TEST_F(LaptopLinkTest, TheReplicatorCopiesOnceAReplicationPeriodWhateverTheStep) {
  setenv("RTDB_KEY", std::to_string(0x5E000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  LaptopSide side;
  side.replicate_period_s = 0.1;
  LaptopLink link(resolve_laptop(side, 2, false), {1, 2}, coach(2));
  ASSERT_NE(link.replicator_stats(), nullptr);
  for (int ms = 0; ms <= 1000; ms += 10) link.step(std::chrono::milliseconds(ms), coach(2));
  EXPECT_EQ(link.replicator_stats()->cycles, 11u) << "at 0, 100, ..., 1000 ms; not at each 10 ms step";
}

TEST_F(LaptopLinkTest, TheSecondTeamsPmanIsCanhilsOwnAtItsOwnKeys) {
  setenv("RTDB_KEY", std::to_string(0x5D000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  LaptopSide side;
  side.pman = "builtin";
  LaptopLink first(resolve_laptop(side, 1, true), {1}, coach(1), 0);
  LaptopLink second(resolve_laptop(side, 1, true), {1}, coach(1), 1);
  ASSERT_NE(second.masters(), nullptr) << "agent 1 of each team: two tables";
  EXPECT_EQ(second.masters()->query(1).at(0).name, "agent1");
  EXPECT_NE(second.masters()->description().find("second team"), std::string::npos);
  LaptopSide library;
  library.pman = "/opt/team/lib/libpman.so";  // refused before it is loaded
  try {
    LaptopLink refused(resolve_laptop(library, 1, true), {2}, coach(1), 1);
    FAIL() << "a team's PMan library for the second team";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("pman = \"builtin\" or \"none\""), std::string::npos) << e.what();
  }
}

TEST_F(LaptopLinkTest, EachRobotsPmanTableIsTickedAfterItsVisionInfo) {
  LaptopLink link(team(true), {1}, coach(1));
  ASSERT_NE(link.masters(), nullptr);
  const auto processes = link.masters()->query(1);
  ASSERT_EQ(processes.size(), 1u);
  EXPECT_EQ(processes[0].name, "agent1") << "registered before anything else runs";
  link.vision_frame(0, frame());
  link.vision_frame(0, frame());
  EXPECT_EQ(link.masters()->counts(1).at(0).activations, 0u) << "no client attached: nobody to wake";
  EXPECT_NE(link.summary().find("agent 1 agent1: 0 activations"), std::string::npos) << link.summary();
}

TEST_F(LaptopLinkTest, TheFrameSignalGoesToTheAgentsSpaceInItsSetAndWaitsForActivateWhenDeferred) {
  // An agent of the second team on canhil's RTDB (AGENT=1, SECOND_RTDB=1), in a
  // child process, asks without waiting whether its frame signal came; the
  // pipes order the two processes, no clock does.
  setenv("RTDB_KEY", std::to_string(0x5E000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  LaptopLink link(resolve_laptop({}, 1, false), {1}, coach(1), 1);
  link.signal_frames(true);
  link.defer_activation(true);
  int to_child[2];
  int to_parent[2];
  ASSERT_EQ(pipe(to_child), 0);
  ASSERT_EQ(pipe(to_parent), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    setenv("AGENT", "1", 1);
    setenv("SECOND_RTDB", "1", 1);
    char answer = DB_init() == 0 ? 'r' : 'x';
    char go = 0;
    for (int round = 0; round < 2; ++round) {
      if (write(to_parent[1], &answer, 1) != 1 || read(to_child[0], &go, 1) != 1) _exit(2);
      answer = static_cast<char>('0' + DB_wait_frame(0));  // 0 woken, 1 not (yet)
    }
    _exit(write(to_parent[1], &answer, 1) == 1 ? 0 : 2);
  }
  const auto ask = [&](char& answer) {
    const char go = 'g';
    return write(to_child[1], &go, 1) == 1 && read(to_parent[0], &answer, 1) == 1;
  };
  char answer = 0;
  ASSERT_EQ(read(to_parent[0], &answer, 1), 1);
  ASSERT_EQ(answer, 'r') << "the child joined the second set as agent 1";
  link.vision_frame(0, frame());
  ASSERT_TRUE(ask(answer));
  EXPECT_EQ(answer, '1') << "deferred: the frame is written, the agent not yet woken";
  EXPECT_EQ(link.activate(), 1u);
  ASSERT_TRUE(ask(answer));
  EXPECT_EQ(answer, '0') << "activate() posts the frame signal of memory space N + 1";
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

TEST_F(LaptopLinkTest, ATableThatDisagreesWithTheLayoutStopsTheRunNamingTheItem) {
  const auto dir = test::scratch_dir("laptop_link_mismatch");
  std::ifstream in(cambada_like("config/rtdb.ini"));
  std::string ini((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Every robot's VISION_INFO the size of canhil's.
  std::size_t replaced = 0;
  for (auto at = ini.find("2    8052"); at != std::string::npos; at = ini.find("2    8052", at)) {
    ini.replace(at, 9, "2    4852");
    ++replaced;
  }
  ASSERT_EQ(replaced, 6u);
  test::write_file(dir / "rtdb.ini", ini);
  LaptopSide side = team();
  side.rtdb_ini = (dir / "rtdb.ini").string();
  try {
    LaptopLink link(side, {1}, coach(1));
    FAIL() << "a VISION_INFO of the wrong size was accepted";
  } catch (const SetupError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("VISION_INFO"), std::string::npos) << what;
    EXPECT_NE(what.find("8052"), std::string::npos) << what;
    EXPECT_NE(what.find("4852"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace canhil::emulator
