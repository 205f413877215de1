// The reference handler against the emulated nodes over a real vcan:
// `canhil nodes` (emulator), `canhil-hwcomm` (handler) and rtdb_drive (a C
// program linked only against the RTDB library) are separate processes; this
// test watches the bus. Runs through vcan_setup/with-vcan.sh.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <string>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace std::chrono_literals;

struct Process {
  pid_t pid = -1;
  std::string log;
  Process(const std::string& cmd, std::string log_file) : log(std::move(log_file)) {
    pid = fork();
    if (pid == 0) {
      const std::string full = "exec " + cmd + " > " + log + " 2>&1";
      execl("/bin/sh", "sh", "-c", full.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  void stop() {
    if (pid <= 0) return;
    kill(pid, SIGINT);
    waitpid(pid, nullptr, 0);
    pid = -1;
  }
  ~Process() { stop(); }
  std::string output() const {
    std::string out;
    if (FILE* f = std::fopen(log.c_str(), "r")) {
      char buf[512];
      while (std::fgets(buf, sizeof buf, f) != nullptr) out += buf;
      std::fclose(f);
    }
    return out;
  }
};

std::string run(const std::string& cmd) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return out;
  char buf[512];
  while (std::fgets(buf, sizeof buf, p) != nullptr) out += buf;
  pclose(p);
  return out;
}

TEST(VcanHwcomm, HandlerBetweenTheEmulatedNodesAndTheRtdb) {
  setenv("RTDB_KEY", std::to_string(0x5C000000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
  setenv("AGENT", "1", 1);
  const std::string bin = canhil::test::build_dir();
  Process emulator(bin + "/app/canhil nodes --iface vcan0 --quiet", "/tmp/canhil_vcan_hwcomm_nodes.log");
  Process handler(bin + "/laptop/canhil-hwcomm --iface vcan0", "/tmp/canhil_vcan_hwcomm_handler.log");
  // Count M7 on the bus from here.
  auto bus = canhil::can_nodes::SocketCanBus::open("vcan0");
  const canhil::can_nodes::Filter m7[] = {canhil::can_nodes::Filter::exact(0x0B0)};
  bus->set_filters(m7);
  std::atomic<bool> done{false};
  std::atomic<int> m7_seen{0};
  std::thread counter([&] {
    while (!done) {
      if (bus->wait_readable(50ms)) {
        while (bus->receive()) ++m7_seen;
      }
    }
  });
  std::this_thread::sleep_for(1s);  // the emulator's first ECs; the handler attached
  const std::string drive = run(bin + "/tests/rtdb_drive vel 0 0.5 0 2");
  float px = 0, py = 9, pa = 0;
  int age = -1;
  ASSERT_EQ(std::sscanf(drive.c_str(), "CMD_POS %f %f %f age %d", &px, &py, &pa, &age), 4)
      << drive << "\nhandler:\n"
      << handler.output() << "\nemulator:\n"
      << emulator.output();
  EXPECT_NEAR(py, 1.0, 0.25) << "about a metre forward";
  EXPECT_NEAR(px, 0.0, 0.1);
  EXPECT_GE(age, 0);
  EXPECT_LT(age, 200) << "CMD_POS is fresh (M4 every 50 ms)";
  const int before = m7_seen.load();
  const std::string kick = run(bin + "/tests/rtdb_drive kick 168");  // 0x80 | 40: low kick
  EXPECT_NE(kick.find("CMD_KICKER power 0"), std::string::npos) << kick << handler.output();
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(m7_seen.load() - before, 1) << "the kicker command went out exactly once";
  done = true;
  counter.join();
  handler.stop();
  emulator.stop();
  const std::string summary = handler.output();
  EXPECT_NE(summary.find("kicks sent 1"), std::string::npos) << summary;
  EXPECT_NE(summary.find("latency receive timestamp -> RTDB write"), std::string::npos) << summary;
  std::printf("%s", summary.c_str());
}

}  // namespace
