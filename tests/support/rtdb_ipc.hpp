// tests/support/rtdb_ipc.hpp — for the RTDB tests: System V keys of their own
// for every test (canhil's RTDB_KEY and the team stand-in's TEAM_RTDB_KEY,
// derived from the pid, so runs never meet), the check that nothing was left
// behind, and a scratch folder for the rtdb.ini and rtdb_user.h a test writes.
#pragma once

#include <sys/ipc.h>
#include <sys/shm.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/test_paths.hpp"

namespace canhil::test {

class RtdbKeys {
 public:
  static constexpr int kKeysEach = 128;  ///< keys a base spans: 64 agents a set, two sets (teams)

  /// Sets RTDB_KEY and TEAM_RTDB_KEY in the environment to fresh bases: ones
  /// no earlier process left segments under (a process killed before it
  /// cleaned up, whose pid matched this one's low bits, would otherwise fail
  /// this test's check that nothing is left behind).
  RtdbKeys() {
    static int counter = 0;
    for (int tries = 0; tries < 32; ++tries) {
      const int slot = ((getpid() & 0xFFF) << 12) + ((++counter & 0x1F) << 7);
      canhil_ = 0x5B000000 + slot;
      team_ = 0x7E000000 + slot;
      if (leftovers().empty()) break;
    }
    setenv("RTDB_KEY", std::to_string(canhil_).c_str(), 1);
    setenv("TEAM_RTDB_KEY", std::to_string(team_).c_str(), 1);
  }
  int canhil_base() const { return canhil_; }
  int team_base() const { return team_; }

  /// The keys under either base that still have a segment ("" when none).
  std::string leftovers() const {
    std::string out;
    for (const int base : {canhil_, team_}) {
      for (int k = 0; k < kKeysEach; ++k) {
        if (shmget(base + k, 0, 0) >= 0) out += (out.empty() ? "" : ", ") + std::to_string(base + k);
      }
    }
    return out;
  }

 private:
  int canhil_ = 0;
  int team_ = 0;
};

/// A fresh, empty folder under the build tree for one test.
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::path(build_dir()) / "test_scratch" / (name + "-" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_file(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

}  // namespace canhil::test
