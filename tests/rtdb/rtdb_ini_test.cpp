// canhil's librtdb.so with a team's rtdb.ini read at run time, as a CAMBADA
// program uses it: two processes share items through it (one finds the ini
// at ../config/rtdb.ini from its working directory, as CAMBADA's agent
// does); ids, sizes and names as the files say; a malformed ini names its
// file and line. Own System V keys, nothing left behind.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstring>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/database.hpp"
#include "support/team_rtdb.hpp"

namespace canhil::rtdb {
namespace {

using namespace test;  // the team's items and agents

// librtdb.so loaded as a program linked with it would use it.
class Librtdb {
 public:
  Librtdb() : handle_(dlopen(canhil_librtdb().c_str(), RTLD_NOW | RTLD_LOCAL)) {
    if (handle_ == nullptr) throw std::runtime_error(dlerror());
  }
  ~Librtdb() { dlclose(handle_); }
  Librtdb(const Librtdb&) = delete;
  Librtdb& operator=(const Librtdb&) = delete;
  template <class F>
  F fn(const char* name) const {
    void* p = dlsym(handle_, name);
    if (p == nullptr) throw std::runtime_error(std::string("librtdb.so has no ") + name);
    return reinterpret_cast<F>(p);
  }
  int init() const { return fn<int (*)()>("DB_init")(); }
  void free() const { fn<void (*)()>("DB_free")(); }
  int init_all() const { return fn<int (*)(int)>("DB_init_all")(0); }
  void free_all() const { fn<void (*)(int)>("DB_free_all")(0); }
  int put(int id, void* v) const { return fn<int (*)(int, void*)>("DB_put")(id, v); }
  int get(int from, int id, void* v) const { return fn<int (*)(int, int, void*)>("DB_get")(from, id, v); }
  int put_in(int a, int to, int id, void* v, int life) const {
    return fn<int (*)(int, int, int, void*, int)>("DB_put_in")(a, to, id, v, life);
  }
  void set_config_file(const char* f) const { fn<void (*)(const char*)>("DB_set_config_file")(f); }
  int item_count() const { return fn<int (*)()>("DB_item_count")(); }
  int item_size(int id) const { return fn<int (*)(int)>("DB_item_size")(id); }
  int item_shared(int a, int id) const { return fn<int (*)(int, int)>("DB_item_shared")(a, id); }
  std::string item_name(int id) const {
    const char* n = fn<const char* (*)(int)>("DB_item_name")(id);
    return n != nullptr ? n : "(null)";
  }
  std::string agent_name(int a) const {
    const char* n = fn<const char* (*)(int)>("DB_agent_name")(a);
    return n != nullptr ? n : "(null)";
  }

 private:
  void* handle_;
};

class RuntimeIni : public ::testing::Test {
 protected:
  void SetUp() override {
    files_ = write_team_files(::testing::UnitTest::GetInstance()->current_test_info()->name());
    setenv("AGENT", "1", 1);
    unsetenv("CANHIL_RTDB_INI");
    unsetenv("CANHIL_RTDB_USER_H");
  }
  void TearDown() override {
    unsetenv("CANHIL_RTDB_INI");
    unsetenv("CANHIL_RTDB_USER_H");
    EXPECT_EQ(keys_.leftovers(), "") << "segments left behind";
  }
  RtdbKeys keys_;
  TeamFiles files_;
};

// Child: the team's agent, run from bin/ next to config/ (no ini named).
// Writes CMD_VEL and ROBOT_WS, then checks the VISION_INFO the parent wrote.
int agent_child(int to_parent, int from_parent, const std::filesystem::path& bin) {
  if (chdir(bin.c_str()) != 0) return 10;
  const Librtdb lib;
  if (lib.init() != 0) return 11;
  std::array<unsigned char, 16> vel{};
  vel.fill(3);
  std::array<unsigned char, 20> ws{};
  ws.fill(4);
  if (lib.put(kCmdVel, vel.data()) != 16 || lib.put(kRobotWs, ws.data()) != 20) return 12;
  char c = 'w';
  if (write(to_parent, &c, 1) != 1 || read(from_parent, &c, 1) != 1) return 13;
  std::vector<unsigned char> vision(8052);
  const int age = lib.get(3333 /* SELF */, kVisionInfo, vision.data());
  const bool ok = age >= 0 && vision[0] == 5 && vision[8051] == 6;
  lib.free();
  return ok ? 0 : 14;
}

TEST_F(RuntimeIni, TwoProcessesShareItemsThroughLibrtdb) {
  int to_parent[2];
  int to_child[2];
  ASSERT_EQ(pipe(to_parent), 0);
  ASSERT_EQ(pipe(to_child), 0);
  std::fflush(nullptr);
  const pid_t child = fork();
  if (child == 0) _exit(agent_child(to_parent[1], to_child[0], files_.dir / "bin"));
  char c = 0;
  ASSERT_EQ(read(to_parent[0], &c, 1), 1);
  {
    auto db =
        open_library(canhil_librtdb(), ItemTable::from_files(files_.user_h, files_.ini), Scope::kAllAgents, files_.ini);
    std::array<unsigned char, 16> vel{};
    EXPECT_GE(db->get(kRobot1, kRobot1, kCmdVel, std::as_writable_bytes(std::span(vel))), 0);
    EXPECT_EQ(vel[15], 3) << "the child's CMD_VEL";
    std::vector<unsigned char> vision(8052);
    vision.front() = 5;
    vision.back() = 6;
    db->put(kRobot1, kRobot1, kVisionInfo, std::as_bytes(std::span(vision)));
    ASSERT_EQ(write(to_child[1], "d", 1), 1);
    int status = 0;
    waitpid(child, &status, 0);
    EXPECT_TRUE(WIFEXITED(status)) << status;
    EXPECT_EQ(WEXITSTATUS(status), 0) << "the child's check failed (its exit code says which)";
  }
  for (const int fd : {to_parent[0], to_parent[1], to_child[0], to_child[1]}) close(fd);
}

TEST_F(RuntimeIni, IdsSizesAndNamesAsTheFilesSay) {
  {
    const Librtdb lib;
    lib.set_config_file(files_.ini.c_str());
    EXPECT_EQ(lib.item_count(), 6);
    EXPECT_EQ(lib.item_size(kVisionInfo), 8052);
    EXPECT_EQ(lib.item_size(kUnusedItem), -1) << "an id the ini leaves out";
    EXPECT_EQ(lib.item_shared(kBaseStation, kCoachInfo), 1);
    EXPECT_EQ(lib.item_shared(kRobot2, kCoachInfo), 0);
    EXPECT_EQ(lib.item_shared(kBaseStation, kCmdVel), -1);
    EXPECT_EQ(lib.agent_name(kRobot2), "ROBOT_2");
    EXPECT_EQ(lib.item_name(kCmdPos), "item5") << "an rtdb.ini has no item names";
    ASSERT_EQ(lib.init_all(), 0);
    std::vector<unsigned char> vision(8052);
    EXPECT_EQ(lib.put_in(kRobot2, kRobot2, kVisionInfo, vision.data(), 0), 8052);
    EXPECT_EQ(lib.put_in(kBaseStation, kRobot2, kVisionInfo, vision.data(), 0), -1) << "robot 2's local item";
    lib.free_all();
  }
  setenv("CANHIL_RTDB_INI", files_.ini.c_str(), 1);  // the library's own variable
  setenv("CANHIL_RTDB_USER_H", files_.user_h.c_str(), 1);
  const Librtdb lib;
  EXPECT_EQ(lib.item_name(kCmdPos), "CMD_POS");
  EXPECT_EQ(lib.item_name(kUnusedItem), "UNUSED_ITEM");
  EXPECT_EQ(lib.item_size(kCmdPos), 24);
}

TEST_F(RuntimeIni, AMalformedIniNamesFileAndLine) {
  write_file(files_.ini, "# 0 BASE_STATION\n1 64 1 s\n\n# 1 ROBOT_1\n0 20 1 s\n3 16 one l\n");
  const Librtdb lib;
  lib.set_config_file(files_.ini.c_str());
  testing::internal::CaptureStderr();
  EXPECT_EQ(lib.init_all(), -1);
  EXPECT_EQ(lib.item_count(), 0) << "no table";
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find(files_.ini.string() + ":6: expected an item line \"ID SIZE PERIOD s|l\""), std::string::npos)
      << said;
  // Without an ini named, the library says where it looked.
  lib.set_config_file(nullptr);
  const auto cwd = std::filesystem::current_path();
  ASSERT_EQ(chdir(files_.dir.c_str()), 0);  // no ../config/rtdb.ini from here
  testing::internal::CaptureStderr();
  EXPECT_EQ(lib.init(), -1);
  const std::string where = testing::internal::GetCapturedStderr();
  EXPECT_NE(where.find("../config/rtdb.ini: cannot read the item table"), std::string::npos) << where;
  EXPECT_NE(where.find("$CANHIL_RTDB_INI"), std::string::npos) << where;
  std::filesystem::current_path(cwd);
}

TEST_F(RuntimeIni, ATableWithOtherSizesIsRefused) {
  // The table says VISION_INFO is canhil's 4852 bytes; the library's ini 8052.
  std::string ini = team_rtdb_ini();
  for (std::size_t at; (at = ini.find("8052")) != std::string::npos;) ini.replace(at, 4, "4852");
  write_file(files_.dir / "canhil.ini", ini);
  const auto table = ItemTable::from_files(files_.user_h, files_.dir / "canhil.ini");
  try {
    open_library(canhil_librtdb(), table, Scope::kAllAgents, files_.ini);
    FAIL() << "opened";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find(canhil_librtdb() + " has item VISION_INFO with 8052 bytes, " + table.source() +
                                         " with 4852"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace canhil::rtdb
