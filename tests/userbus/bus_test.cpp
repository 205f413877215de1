// The user-space bus from canhil's side (userbus/bus.hpp) and with real,
// unchanged programs on it: can-utils, python-can, a process killed in the
// middle of its writes, the time shim beside the bus's preload. Each test
// starts its own bus in a folder of its own, owned by this process.
#include "canhil/userbus/bus.hpp"

#include <linux/can.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bus_support.hpp"
#include "canhil/userbus/state.hpp"
#include "support/test_paths.hpp"

namespace {

namespace fs = std::filesystem;
namespace ub = canhil::userbus;
using canhil::test::beside;
using canhil::test::OwnBus;
using canhil::test::shell;
using canhil::test::until_bound;

TEST_F(OwnBus, StartsListsAndStops) {
  EXPECT_FALSE(ub::broker_alive(paths_));
  start();
  EXPECT_TRUE(ub::broker_alive(paths_));
  struct stat st {};
  ASSERT_EQ(stat(folder_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0700U);
  ASSERT_EQ(stat(paths_.state.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600U);
  const std::string listed = ub::describe(paths_);
  EXPECT_NE(listed.find("vcan0  index 1048576  up  mtu 72"), std::string::npos) << listed;
  EXPECT_NE(listed.find("vcan1"), std::string::npos) << listed;
  ub::set_interface_up(paths_, "vcan1", false);
  EXPECT_NE(ub::describe(paths_).find("vcan1  index 1048577  down"), std::string::npos);
  ub::remove_interfaces(paths_, {"vcan1"});
  EXPECT_EQ(ub::describe(paths_).find("vcan1"), std::string::npos);
  EXPECT_THROW(ub::remove_interfaces(paths_, {"vcan9"}), ub::BusError);
  EXPECT_THROW(ub::start_broker(paths_, {}), ub::BusError);  // one bus per folder
  ub::stop_broker(paths_);
  EXPECT_FALSE(ub::broker_alive(paths_));
  EXPECT_FALSE(fs::exists(paths_.state));
}

TEST_F(OwnBus, BusUpSaysItsBrokersSchedulingAndOptionsAndRefusesBadOnes) {
  const std::string canhil = "CANHIL_BUS_DIR='" + folder_.string() + "' " + canhil::test::canhil_binary();
  int status = -1;
  const std::string up = shell(canhil + " bus up vcan0 --backlog 100 --grace-ms 5 --patience-ms 50", &status);
  EXPECT_EQ(status, 0) << up;
  EXPECT_NE(up.find("grace 5 ms, patience 50 ms, backlog 100 frames"), std::string::npos) << up;
  // Root or CAP_SYS_NICE gets the real-time priority, others the normal scheduler: either is said.
  EXPECT_TRUE(up.find("SCHED_FIFO 45, memory locked") != std::string::npos ||
              up.find("normal scheduler") != std::string::npos)
      << up;
  EXPECT_NE(up.find("waited for full receivers 0 time(s)"), std::string::npos) << up;
  shell(canhil + " bus down");
  for (const char* bad : {"--rt-priority 120", "--backlog 0", "--grace-ms -1", "--patience-ms 20000"}) {
    const std::string out = shell(canhil + " bus up vcan0 " + bad, &status);
    EXPECT_EQ(status, 2) << bad << "\n" << out;
    EXPECT_FALSE(ub::broker_alive(paths_)) << bad << ": no bus started";
  }
}

TEST_F(OwnBus, RefusesBadNamesAndAFolderOthersCanOpen) {
  EXPECT_THROW(ub::check_interface_name(""), ub::BusError);
  EXPECT_THROW(ub::check_interface_name("a_name_of_16_chr"), ub::BusError);
  EXPECT_THROW(ub::check_interface_name("vcan 0"), ub::BusError);
  EXPECT_THROW(ub::check_interface_name("vcan/0"), ub::BusError);
  fs::create_directories(folder_);
  fs::permissions(folder_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec);
  try {
    ub::start_broker(paths_, {});
    FAIL() << "a folder others can open was used";
  } catch (const ub::BusError& e) {
    EXPECT_NE(std::string(e.what()).find("0700"), std::string::npos) << e.what();
  }
}

TEST_F(OwnBus, ReclaimsTheFilesOfABrokerThatDied) {
  start();
  ASSERT_EQ(kill(broker_, SIGKILL), 0);
  waitpid(broker_, nullptr, 0);
  EXPECT_TRUE(fs::exists(paths_.socket));  // left behind
  EXPECT_FALSE(ub::broker_alive(paths_));
  start({"vcan0"});
  EXPECT_TRUE(ub::broker_alive(paths_));
  EXPECT_NE(ub::describe(paths_).find("vcan0"), std::string::npos);
}

TEST_F(OwnBus, ABrokerKilledAndNotReapedIsNoBus) {
  // As in a container whose first process reaps nobody: the dead broker is a
  // zombie, its pid still answers kill(), its files are still there. A
  // preloaded program gets the kernel's answer, as without a bus (docs/vcan.md),
  // not ENOBUFS from a socket nobody listens on.
  start({"vcan0"});
  ASSERT_EQ(kill(broker_, SIGKILL), 0);
  for (int k = 0; k < 500 && ub::broker_alive(paths_); ++k) usleep(2000);
  ASSERT_EQ(kill(broker_, 0), 0) << "a zombie still";
  int with = -1;
  int without = -1;
  const std::string preloaded = on_bus("cansend vcan0 123#11", &with);
  const std::string plain = shell("cansend vcan0 123#11", &without);
  EXPECT_EQ(preloaded.find("No buffer space"), std::string::npos) << preloaded;
  EXPECT_EQ(with, without);
  EXPECT_EQ(preloaded, plain);
  waitpid(broker_, nullptr, 0);
}

TEST_F(OwnBus, EndsWithItsOwner) {
  const pid_t owner = fork();
  if (owner == 0) {
    usleep(300000);
    _exit(0);
  }
  ub::BrokerOptions o;
  o.owner = owner;
  broker_ = ub::start_broker(paths_, o);
  EXPECT_TRUE(ub::broker_alive(paths_));
  waitpid(owner, nullptr, 0);
  int status = 0;
  EXPECT_EQ(waitpid(broker_, &status, 0), broker_);  // it ended by itself
  EXPECT_FALSE(ub::broker_alive(paths_));
  EXPECT_FALSE(fs::exists(paths_.socket));
}

TEST_F(OwnBus, ItsBrokerSpinsOnlyWhileARunThatAskedLives) {
  start({"vcan0"});
  const auto mapped = ub::MappedState::open(paths_);
  ASSERT_NE(mapped, nullptr);
  ub::State& state = mapped->state();
  // The broker counts each time it looks for a next frame before sleeping;
  // a frame sent wakes it (a connection, its hello, the frame, its close).
  // A first frame settles it: a socket's hello waits for the broker, so a
  // look it began before is counted by the time the first cansend is done.
  const auto spins_after_a_frame = [&] {
    EXPECT_EQ(on_bus("cansend vcan0 7FF#"), "");
    const std::uint64_t before = state.spins.load();
    EXPECT_EQ(on_bus("cansend vcan0 123#11"), "");
    return state.spins.load() - before;
  };
  EXPECT_EQ(state.spin.load(), 0U) << "a bus starts sleeping at once";
  EXPECT_EQ(spins_after_a_frame(), 0U);
  {
    const ub::BrokerSpin spin(paths_, 50);
    EXPECT_EQ(state.spin.load(), ub::spin_word(getpid(), 50));
    EXPECT_EQ(ub::spin_pid(state.spin.load()), getpid());
    EXPECT_EQ(ub::spin_us(state.spin.load()), 50U);
    EXPECT_GT(spins_after_a_frame(), 0U);
  }
  EXPECT_EQ(state.spin.load(), 0U) << "given back when the run ends";
  EXPECT_EQ(spins_after_a_frame(), 0U);
  // A run that ended without giving it back, reaped or not: the broker sleeps at once.
  for (const bool reaped : {false, true}) {
    const pid_t gone = fork();
    if (gone == 0) _exit(0);
    if (reaped) {
      waitpid(gone, nullptr, 0);
    } else {
      siginfo_t info{};
      waitid(P_PID, static_cast<id_t>(gone), &info, WEXITED | WNOWAIT);  // ended, a zombie still
    }
    state.spin.store(ub::spin_word(gone, 50));
    EXPECT_EQ(spins_after_a_frame(), 0U) << (reaped ? "reaped" : "not reaped yet");
    if (!reaped) waitpid(gone, nullptr, 0);
  }
  // A run that took the bus over after this one: its setting outlives this one's end.
  {
    const ub::BrokerSpin spin(paths_, 50);
    state.spin.store(ub::spin_word(broker_, 60));  // alive, and not this process
  }
  EXPECT_EQ(state.spin.load(), ub::spin_word(broker_, 60));
  EXPECT_GT(spins_after_a_frame(), 0U);
  state.spin.store(0);
  EXPECT_THROW(ub::BrokerSpin(ub::BusPaths{"/nonexistent", "/nonexistent/bus.sock", "/nonexistent/state"}, 50),
               ub::BusError);
}

TEST_F(OwnBus, ABusOfAnotherCanhilIsNamedSo) {
  start({"vcan0"});
  {
    const auto mapped = ub::MappedState::open(paths_);
    ASSERT_NE(mapped, nullptr);
    mapped->state().version = ub::kVersion - 1;  // as an older canhil left it
  }
  EXPECT_EQ(ub::MappedState::open(paths_), nullptr);
  try {
    ub::describe(paths_);
    ADD_FAILURE() << "a state of another version read";
  } catch (const ub::BusError& e) {
    EXPECT_NE(std::string(e.what()).find("was started by another canhil (its state is version " +
                                         std::to_string(ub::kVersion - 1) + ", this canhil's " +
                                         std::to_string(ub::kVersion) + "): stop it (`canhil bus down`)"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(OwnBus, KeepsNoDescriptorOfItsStarter) {
  // A pipe's write end open when the broker starts: once this process closes
  // it, the read end sees the end at once, since the broker holds no copy
  // (a match's worker is known to have ended by such a pipe).
  int ends[2];
  ASSERT_EQ(pipe(ends), 0);
  start();
  close(ends[1]);
  pollfd p{ends[0], POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 2000), 1);
  EXPECT_NE(p.revents & POLLHUP, 0) << "the pipe's end reached: nobody else holds its write end";
  close(ends[0]);
  EXPECT_TRUE(ub::broker_alive(paths_)) << "its own listening socket kept";
}

TEST_F(OwnBus, CangenIntoCandumpLosesNothing) {
  start({"vcan0"});
  int status = -1;
  // candump reading before the flood (a frame it read first), and read
  // to the end before it is stopped (its log quiet).
  const std::string out =
      on_bus(beside("candump -l vcan0",
                    canhil::test::until_reading("p", "cansend vcan0 7FF#5741524D") +
                        "cangen vcan0 -g 0 -n 100000 -I i -L 8 -D i; " + canhil::test::until_quiet("candump-*.log"),
                    true, "cat candump-*.log"),
             &status);
  EXPECT_EQ(status, 0) << out.substr(0, 500);
  std::istringstream lines(out);
  std::string line;
  std::size_t frames = 0;
  bool in_order = true;
  bool first = true;
  while (std::getline(lines, line)) {
    const auto hash = line.find('#');
    if (line.empty() || line[0] != '(' || hash == std::string::npos) continue;
    if (first) {  // the frame that showed candump reading
      EXPECT_NE(line.find("7FF#5741524D"), std::string::npos) << "the first frame logged: " << line;
      first = false;
      continue;
    }
    // -I i: the ids count up modulo 0x800, in order
    const unsigned id = static_cast<unsigned>(std::stoul(line.substr(hash - 3, 3), nullptr, 16));
    in_order = in_order && id == (frames & 0x7FF);
    ++frames;
  }
  EXPECT_EQ(frames, 100000U);
  EXPECT_TRUE(in_order);
}

/// The lines of file `name` in the test's bus folder.
std::size_t lines_of(const fs::path& folder, const std::string& name) {
  std::ifstream in(folder / name);
  std::size_t n = 0;
  std::string line;
  while (std::getline(in, line)) ++n;
  return n;
}

TEST_F(OwnBus, AReceiverStoppedForAWhileLosesNothingAndStallsNobody) {
  // Two candumps; one is stopped (SIGSTOP: not runnable, so not waited for)
  // while 2000 frames pass, more than its buffer holds: they wait in the
  // broker's backlog for it, and the bus never waits (a real-time run's
  // observer, starved for a while on a busy machine, slows nobody). With a
  // grace alone the stopped one lost frames after 10 ms.
  start({"vcan0"});
  const std::string out = on_bus(
      "candump -L vcan0 > a.log & a=$!; candump -L vcan0 > b.log & b=$!; " + until_bound("a") + until_bound("b") +
      "kill -STOP $b; cangen vcan0 -g 0.25 -n 2000 -I i -L 8 -D i; sleep 0.2; kill -CONT $b; sleep 0.5; "
      "kill -INT $a $b; wait");
  EXPECT_EQ(lines_of(folder_, "a.log"), 2000U) << out;
  EXPECT_EQ(lines_of(folder_, "b.log"), 2000U) << out;
  EXPECT_EQ(ub::broker_waits(paths_).count, 0U);
  EXPECT_EQ(ub::interface_counts(paths_).at(0).dropped, 0U);
}

TEST_F(OwnBus, ASocketThatNeverReadsCostsTheBusNoWait) {
  // A program that binds a socket taking every frame and never reads it:
  // flooded by cangen, frames are dropped for it, counted, without the bus
  // waiting for it as for a reader.
  start({"vcan0"});
  const std::string out = on_bus(
      "/usr/bin/python3 -c \"import socket, time; s = socket.socket(socket.PF_CAN, socket.SOCK_RAW, socket.CAN_RAW); "
      "s.bind((\\\"vcan0\\\",)); time.sleep(3)\" & q=$!; " +
      until_bound("q") + "cangen vcan0 -g 0 -n 8000 -L 8; wait $q");
  EXPECT_EQ(ub::broker_waits(paths_).count, 0U) << out;
  EXPECT_GT(ub::interface_counts(paths_).at(0).dropped, 0U) << "the quiet cangen's buffer and backlog overflowed";
}

TEST_F(OwnBus, CansendSeenByCandumpOnEveryInterfaceAndCanbusloadMeasures) {
  start();
  const std::string out = on_bus(
      beside("candump -n 2 any > any.txt", "cansend vcan0 123#11; cansend vcan1 1ABCDEF0#2233", false, "cat any.txt"));
  EXPECT_NE(out.find("vcan0  123   [1]  11"), std::string::npos) << out;
  EXPECT_NE(out.find("vcan1  1ABCDEF0   [2]  22 33"), std::string::npos) << out;
  const std::string load =
      on_bus(beside("canbusload vcan0@500000 > load.txt", "cangen vcan0 -g 1 -n 200; sleep 1.2", true, "cat load.txt"));
  EXPECT_NE(load.find("vcan0@500000"), std::string::npos) << load;
}

TEST_F(OwnBus, CanplayerReplaysALogAndCansnifferWatches) {
  start();
  // canplayer sends each frame to the interface its log line names (sendto on a socket bound to all)
  const std::string played = on_bus(
      std::string("printf \"(1.000000) vcan0 101#01\\n(1.010000) vcan1 202#0202\\n(1.020000) vcan0 303#030303\\n\" > "
                  "play.log; ") +
      beside("candump -n 3 any > seen.txt", "canplayer -I play.log", false, "cat seen.txt"));
  EXPECT_NE(played.find("vcan0  101   [1]  01"), std::string::npos) << played;
  EXPECT_NE(played.find("vcan1  202   [2]  02 02"), std::string::npos) << played;
  EXPECT_NE(played.find("vcan0  303   [3]  03 03 03"), std::string::npos) << played;
  // cansniffer reads the bus and draws its table of ids
  const std::string sniffed = on_bus(
      beside("cansniffer -c vcan0 > sniff.txt", "cangen vcan0 -g 10 -n 40 -I 5A5; sleep 1.2", true, "cat sniff.txt"));
  EXPECT_NE(sniffed.find("5A5"), std::string::npos) << sniffed.substr(0, 400);
}

TEST_F(OwnBus, PythonCanSendsAndReceivesWithFilters) {
  start({"vcan0"});
  int status = -1;
  const std::string out =
      on_bus("/usr/bin/python3 " + canhil::test::source_dir() + "/tests/userbus/python_can_check.py", &status);
  EXPECT_EQ(status, 0) << out;
  EXPECT_NE(out.find("python-can: 1 of 5 frames through the filter, 0x123 [3, 1, 2] on vcan0"), std::string::npos)
      << out;
}

TEST_F(OwnBus, AProcessKilledMidWriteLeavesTheBusUsable) {
  start({"vcan0"});
  // cangen writes as fast as it can; SIGKILL lands in the middle of its writes.
  const std::string killed = on_bus("cangen vcan0 -g 0 & p=$!; sleep 0.3; kill -KILL $p; wait $p; echo killed");
  EXPECT_NE(killed.find("killed"), std::string::npos);
  // its socket is gone from the bus (the broker saw its connection close)
  for (int k = 0; k < 100 && ub::describe(paths_).find("cangen") != std::string::npos; ++k) usleep(10000);
  EXPECT_EQ(ub::describe(paths_).find("cangen"), std::string::npos) << ub::describe(paths_);
  const std::string out = on_bus(beside("candump -n 1 vcan0", "cansend vcan0 321#AA", false));
  EXPECT_NE(out.find("vcan0  321   [1]  AA"), std::string::npos) << out;
}

TEST_F(OwnBus, BesideTheTimeShimInOneProcess) {
  start({"vcan0"});
  const std::string out =
      on_bus(beside("candump -n 1 vcan0", "LD_PRELOAD=$LD_PRELOAD:$TIMESHIM cansend vcan0 456#BEEF", false));
  EXPECT_NE(out.find("vcan0  456   [2]  BE EF"), std::string::npos) << out;
}

TEST_F(OwnBus, CanhilFindsTheBusByItself) {
  start({"vcan0"});
  // canhil dump started with no preload: where the kernel has no CAN it starts again on the bus.
  const std::string command = "cd '" + folder_.string() + "' && CANHIL_BUS_DIR='" + folder_.string() + "' " +
                              canhil::test::canhil_binary() +
                              " dump vcan0 --count 1 2>&1 & sleep 1; LD_PRELOAD=" + canhil::test::bus_preload() +
                              " CANHIL_BUS_DIR='" + folder_.string() + "' cansend vcan0 2A5#0102; wait";
  const std::string out = shell(command);
  const int probe = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe >= 0) {
    close(probe);  // a kernel with CAN: its interfaces are the ones, canhil does not join the bus
    EXPECT_EQ(out.find("running on canhil's user-space bus"), std::string::npos) << out;
  } else {
    EXPECT_NE(out.find("this kernel has no CAN; running on canhil's user-space bus"), std::string::npos) << out;
    EXPECT_NE(out.find("vcan0 2A5#0102"), std::string::npos) << out;
  }
}

TEST_F(OwnBus, WithoutABusTheKernelAnswers) {
  // No bus runs: the preload steps aside, and the program gets the kernel's own answer.
  fs::create_directories(folder_);
  int with = -1;
  int without = -1;
  const std::string preloaded = on_bus("cansend nobus7 123#11", &with);
  const std::string plain = shell("cansend nobus7 123#11", &without);
  EXPECT_NE(with, 0);
  EXPECT_EQ(with, without);
  EXPECT_EQ(preloaded, plain);
}

}  // namespace
