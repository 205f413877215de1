// tests/support/team_rtdb.hpp — a team's RTDB configuration for the tests (its
// generated rtdb_user.h and rtdb.ini, in CAMBADA's formats), the libraries
// that serve it (the stand-in team library, tests/support/team_rtdb/, and
// canhil's librtdb.so) and the stand-in's put counters.
#pragma once

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "support/rtdb_ipc.hpp"

namespace canhil::test {

inline std::string team_rtdb_library() { return CANHIL_TEST_TEAM_RTDB; }
inline std::string team_rtdb_incomplete_library() { return CANHIL_TEST_TEAM_RTDB_INCOMPLETE; }
inline std::string canhil_librtdb() { return CANHIL_TEST_LIBRTDB; }

/// The team's item ids, as its rtdb_user.h numbers them.
enum TeamItem { kRobotWs = 0, kCoachInfo = 1, kVisionInfo = 2, kCmdVel = 3, kUnusedItem = 4, kCmdPos = 5 };
enum TeamAgent { kBaseStation = 0, kRobot1 = 1, kRobot2 = 2 };

/// The header as CAMBADA's generator writes it (tabs, comments, guard).
/// UNUSED_ITEM is declared but no schema has it, like CAMBADA's REMOTE_CMD.
inline const char* team_user_h() {
  return "/* AUTOGEN FILE : rtdb_user.h */\n\n#ifndef _TEAM_RTDB_USER_\n#define _TEAM_RTDB_USER_\n\n"
         "/* agents section */\n\n#define BASE_STATION\t0\n#define ROBOT_1\t1\n#define ROBOT_2\t2\n\n"
         "#define N_AGENTS\t3\n\n/* items section */\n\n#define ROBOT_WS\t0\n#define COACH_INFO\t1\n"
         "#define VISION_INFO\t2\n#define CMD_VEL\t3\n#define UNUSED_ITEM\t4\n#define CMD_POS\t5\n\n"
         "#define N_ITEMS\t6\n\n#endif\n\n/* EOF : rtdb_user.h */\n";
}

/// Its rtdb.ini (line 6 starts the base station, 9 robot 1, 16 robot 2; CMD_POS is on line 14).
inline const char* team_rtdb_ini() {
  return "##\n## rtdb.ini IS AN AUTOGEN FILE, DO NOT EDIT. \n##\n\n\n"
         "# 0    BASE_STATION\n1    64       1   s\n\n"
         "# 1    ROBOT_1\n0    20       1   s\n1    64       1   l\n2    8052     1   l\n3    16       1   l\n"
         "5    24       1   l\n\n"
         "# 2    ROBOT_2\n0    20       1   s\n1    64       1   l\n2    8052     1   l\n3    16       1   l\n"
         "5    24       1   l\n\n";
}

struct TeamFiles {
  std::filesystem::path dir;
  std::filesystem::path user_h;  ///< dir/rtdb_user.h
  std::filesystem::path ini;     ///< dir/config/rtdb.ini (CAMBADA's place: ../config from dir/bin)
};

/// Writes the team's files into a fresh scratch folder (dir/bin exists too).
inline TeamFiles write_team_files(const std::string& name) {
  TeamFiles f;
  f.dir = scratch_dir(name);
  f.user_h = f.dir / "rtdb_user.h";
  f.ini = f.dir / "config" / "rtdb.ini";
  write_file(f.user_h, team_user_h());
  write_file(f.ini, team_rtdb_ini());
  std::filesystem::create_directories(f.dir / "bin");
  return f;
}

/// The stand-in's count of puts of item `id` into space `space` (-1: no such segment).
inline int standin_put_count(int space, int id) {
  void* h = dlopen(team_rtdb_library().c_str(), RTLD_NOW | RTLD_LOCAL);
  if (h == nullptr) throw std::runtime_error("cannot load the stand-in");
  auto* count = reinterpret_cast<int (*)(int, int)>(dlsym(h, "standin_put_count"));
  const int n = count != nullptr ? count(space, id) : -2;
  dlclose(h);
  return n;
}

}  // namespace canhil::test
