// tests/userbus/bus_support.hpp — what the user-space bus's suites share: a
// shell line's output, a listener beside actions, and a bus of the test's own.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "canhil/userbus/bus.hpp"
#include "support/test_paths.hpp"

namespace canhil::test {

namespace fs = std::filesystem;
namespace ub = canhil::userbus;

/// `line` run by /bin/sh, its standard output and error; its exit status in `status`.
inline std::string shell(const std::string& line, int* status = nullptr) {
  std::string out;
  FILE* p = popen((line + " 2>&1").c_str(), "r");
  if (p == nullptr) return out;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, p)) > 0) out.append(buffer, n);
  const int s = pclose(p);
  if (status != nullptr) *status = WIFEXITED(s) ? WEXITSTATUS(s) : 128 + WTERMSIG(s);
  return out;
}

/// A shell line that waits until `canhil bus list` has a line matching
/// `pattern` (grep's), at most 30 s; then it goes on either way.
inline std::string until_listed(const std::string& pattern) {
  return "k=0; until " + canhil_binary() + " bus list 2>/dev/null | grep -q \"" + pattern +
         "\"; do k=$((k+1)); [ $k -gt 600 ] && break; sleep 0.05; done; ";
}

/// A shell line that waits until the process whose pid is in shell variable
/// `pid` has a socket bound on the bus, as `canhil bus list` shows it (a
/// fixed sleep was too short for a loaded machine's sanitizer build, whose
/// listener missed the first frames); past 30 s it goes on, and the test's
/// counts say what was missed.
inline std::string until_bound(const std::string& pid) { return until_listed("pid $" + pid + " ([^)]*)  [^u]"); }

/// A shell line that waits until the process whose pid is in shell variable
/// `pid` has read a frame (as `canhil bus list` shows it) after `send`
/// (a shell line putting one on the bus) wrote one: a listener bound but
/// not yet reading, still setting itself up on a busy machine, is a socket
/// that only sends to the bus until then (docs/vcan.md: dropped when full,
/// never waited for). Past 30 s it goes on, as until_bound.
inline std::string until_reading(const std::string& pid, const std::string& send) {
  return send + "; " + until_listed("pid $" + pid + " (.*  read [1-9]");
}

/// A shell line that waits until the files `glob` stop growing for half a
/// second (at most 150 s): a listener that logs them has read all it was
/// sent, however far behind the sender a busy machine left it.
inline std::string until_quiet(const std::string& glob) {
  return "n=-1; k=0; while [ $k -lt 300 ]; do m=$(cat " + glob +
         " 2>/dev/null | wc -c); [ \"$m\" = \"$n\" ] && break; n=$m; k=$((k+1)); sleep 0.5; done";
}

/// A shell line: `listener` started in the background and waited for until
/// it has a socket bound (until_bound), then `actions`; the listener then
/// stopped with SIGINT when `interrupt`, else waited for as it ends by
/// itself; then `after`.
inline std::string beside(const std::string& listener, const std::string& actions, bool interrupt,
                          const std::string& after = "") {
  return listener + " & p=$!; " + until_bound("p") + actions + "; " + (interrupt ? "kill -INT $p; " : "") + "wait $p" +
         (after.empty() ? "" : "; " + after);
}

/// A bus of this test's own: started in a fresh folder, stopped at the end.
class OwnBus : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("canhil-bus-ut-" + std::to_string(getpid()));
    fs::remove_all(folder_);
    setenv("CANHIL_BUS_DIR", folder_.c_str(), 1);
    paths_ = ub::BusPaths::current();
  }
  void TearDown() override {
    ub::stop_broker(paths_);
    fs::remove_all(folder_);
    unsetenv("CANHIL_BUS_DIR");
  }
  void start(const std::vector<std::string>& names = {"vcan0", "vcan1"}) {
    ub::BrokerOptions o;
    o.owner = getpid();
    broker_ = ub::start_broker(paths_, o);
    ub::add_interfaces(paths_, names);
  }
  /// `command` run by sh on the bus (the preload and the bus's folder in its environment); its output.
  std::string on_bus(const std::string& command, int* status = nullptr) const {
    return shell("cd '" + folder_.string() + "' && LD_PRELOAD=" + canhil::test::bus_preload() + " TIMESHIM=" +
                     canhil::test::time_shim() + " CANHIL_BUS_DIR='" + folder_.string() + "' sh -c '" + command + "'",
                 status);
  }
  fs::path folder_;
  ub::BusPaths paths_;
  pid_t broker_ = 0;
};

}  // namespace canhil::test
