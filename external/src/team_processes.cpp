// The team's own processes for a session in virtual time (team_processes.hpp).
#include "canhil/external/team_processes.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "canhil/base/assets.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/laptop_link.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::external {

namespace {

namespace fs = std::filesystem;

// canhil's own laptop programs (canhil-hwcomm, canhil-agent) are found
// without a path: installed beside canhil, or in the build tree's laptop/.
std::string search_path() {
  const fs::path here = program_folder();
  std::string path;
  for (const fs::path& p : {here, here.parent_path() / "laptop"}) {
    std::error_code ec;
    if (!p.empty() && fs::exists(p / "canhil-hwcomm", ec)) path += p.string() + ":";
  }
  const char* old = std::getenv("PATH");
  return path + (old != nullptr ? old : "/usr/bin:/bin");
}

// The program's name in a command line, for a log file's name: "canhil-agent".
std::string program_of(const std::string& command) {
  const std::size_t begin = command.find_first_not_of(' ');
  const std::size_t end = command.find(' ', begin == std::string::npos ? 0 : begin);
  std::string word = begin == std::string::npos ? std::string("process") : command.substr(begin, end - begin);
  word = fs::path(word).filename().string();
  for (char& c : word) {
    if (c != '-' && c != '_' && c != '.' && std::isalnum(static_cast<unsigned char>(c)) == 0) c = '_';
  }
  return word.empty() ? std::string("process") : word;
}

// What one of a team's processes is started with, beyond what all share.
struct Spawn {
  const std::string& command;
  int agent;                  // AGENT
  bool second_set;            // of the second team (its RTDB set: SECOND_RTDB=1)
  const std::string& syslog;  // where its syslog messages go (ExternalSide::syslog, for the shim)
  int log;                    // its stdout and stderr (2: canhil's stderr for both), or -1 to keep canhil's
};

// Starts `launch` with `environment` (NAME=value each) and the search `path`.
pid_t start(const Spawn& launch, const std::vector<std::string>& environment, const std::string& path) {
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid != 0) return pid;
  // It ends with canhil: a canhil (or a match's worker) killed outright leaves
  // no process of the team running on in real time.
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(127);  // canhil ended before the line above
  for (const std::string& e : environment) {
    const auto eq = e.find('=');
    setenv(e.substr(0, eq).c_str(), e.substr(eq + 1).c_str(), 1);
  }
  setenv("AGENT", std::to_string(launch.agent).c_str(), 1);
  setenv("CANHIL_SYSLOG", launch.syslog.c_str(), 1);
  if (launch.second_set) {
    setenv("SECOND_RTDB", "1", 1);
  } else {
    unsetenv("SECOND_RTDB");
  }
  setenv("PATH", path.c_str(), 1);
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
  if (launch.log >= 0) {
    dup2(launch.log, STDOUT_FILENO);
    if (launch.log != STDERR_FILENO) dup2(launch.log, STDERR_FILENO);
  }
  // exec: the process is the command's program itself (its signals reach it,
  // and no shell stays behind in the lockstep).
  const std::string line = "exec " + launch.command;
  execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
  _exit(127);
}

}  // namespace

std::unique_ptr<userbus::BrokerSpin> spin_the_bus(const emulator::Session& session) {
  const double us = session.plan().external.bus_spin_us;
  if (us <= 0 || session.robot_count() == 0 || !can_nodes::on_user_space_bus(session.rig(0).interface)) return nullptr;
  try {
    return std::make_unique<userbus::BrokerSpin>(userbus::BusPaths::current(), static_cast<std::uint32_t>(us));
  } catch (const userbus::BusError&) {
    return nullptr;  // a bus canhil's preload found but cannot map: the run goes on, its broker sleeping at once
  }
}

void require_told_goal(const emulator::Scenario& scenario, bool both_ends, FILE* warn) {
  for (std::size_t t = 0; t < scenario.teams.size(); ++t) {
    const emulator::Team& team = scenario.teams[t];
    if (team.attacks_positive_x && !both_ends) continue;
    const std::vector<std::string>& commands = scenario.external_of(t).processes;
    const bool by_command = std::any_of(commands.begin(), commands.end(),
                                        [](const std::string& c) { return c.find("{goal_x}") != std::string::npos; });
    if (by_command) continue;
    const emulator::LaptopSide side = emulator::resolve_laptop(scenario.laptop_of(t), team.robots, false);
    const rtdb::Layout layout = emulator::load_layout(side.layout);
    if (emulator::layout_tells_attacks(layout)) continue;
    const std::string when = team.attacks_positive_x ? " in the second half (ends change at half time)" : "";
    const std::string what = "team " + team.name + " attacks the -x goal" + when + ", but its layout " + layout.name() +
                             " (" + layout.file() + ") has no COACH_INFO quantity `attacks`";
    if (commands.empty()) {
      std::fprintf(warn,
                   "canhil: warning: %s, and canhil does not start its processes: unless your own start-up tells "
                   "its agents which goal is theirs, they believe they attack +x\n",
                   what.c_str());
      continue;
    }
    throw SetupError(what +
                     " and none of its command lines passes {goal_x}: its software, told nothing, would believe it "
                     "attacks +x and play backwards. Map `attacks` in the team's layout (docs/layouts.md; CAMBADA's "
                     "goalColor) or pass {goal_x} to its agent (docs/teams.md)");
  }
}

TeamProcesses::TeamProcesses(std::vector<std::string> environment, FILE* say, ProcessOutput output)
    : environment_(std::move(environment)), say_(say), output_(std::move(output)) {}

TeamProcesses::~TeamProcesses() { stop_all(); }

std::size_t TeamProcesses::start_all(const emulator::Session& session) {
  const emulator::Scenario& scenario = session.scenario();
  const std::string path = search_path();
  if (output_.folder) {
    std::error_code ec;
    fs::create_directories(*output_.folder, ec);
    if (ec) throw SetupError("cannot make the folder " + *output_.folder + " for the processes' logs: " + ec.message());
  }
  for (const emulator::Launch& l : session.plan().external.launches) {
    Started s;
    s.agent = l.agent;
    s.command = l.command;
    int log = -1;
    std::string log_path;
    if (output_.folder) {
      log_path = (fs::path(*output_.folder) / (output_.prefix + scenario.teams[l.team].name + "-agent" +
                                               std::to_string(s.agent) + "-" + program_of(s.command) + ".log"))
                     .string();
      log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (log < 0) throw SetupError("cannot write the process log " + log_path + ": " + std::strerror(errno));
    }
    const Spawn launch{s.command, s.agent, l.team > 0, l.syslog,
                       log >= 0 ? log : (output_.onto_stderr ? STDERR_FILENO : -1)};
    s.pid = start(launch, environment_, path);
    if (log >= 0) close(log);
    std::fprintf(say_, "  started `%s` for agent %d%s (pid %d)%s%s\n", s.command.c_str(), s.agent,
                 scenario.teams.size() > 1 ? (" of team " + scenario.teams[l.team].name).c_str() : "", s.pid,
                 log_path.empty() ? "" : ", output in ", log_path.c_str());
    started_.push_back(s);
  }
  std::fflush(say_);
  return started_.size();
}

void TeamProcesses::reap(Nanos now) {
  for (Started& s : started_) {
    if (s.ended || s.pid <= 0) continue;
    if (waitpid(s.pid, &s.status, WNOHANG) != s.pid) continue;
    s.ended = true;
    s.ended_at = now;
    std::fprintf(say_, "canhil: `%s` (agent %d, pid %d) ended at t = %.3f s: %s %d\n", s.command.c_str(), s.agent,
                 s.pid, to_seconds(now), WIFSIGNALED(s.status) ? "signal" : "exit status",
                 WIFSIGNALED(s.status) ? WTERMSIG(s.status) : WEXITSTATUS(s.status));
  }
}

std::vector<ProcessEnd> TeamProcesses::ends() const {
  std::vector<ProcessEnd> out;
  for (const Started& s : started_) {
    if (!s.ended) continue;
    const bool signalled = WIFSIGNALED(s.status);
    out.push_back(
        {s.command, s.agent, s.pid, signalled, signalled ? WTERMSIG(s.status) : WEXITSTATUS(s.status), s.ended_at});
  }
  return out;
}

std::string TeamProcesses::not_started() const {
  for (const Started& s : started_) {
    if (!s.ended || !WIFEXITED(s.status)) continue;
    const int code = WEXITSTATUS(s.status);
    if (code != 126 && code != 127) continue;
    return "`" + s.command + "` (agent " + std::to_string(s.agent) + ", pid " + std::to_string(s.pid) +
           ") never ran: the shell found " +
           (code == 127 ? "no such program (exit status 127); check the command line and PATH"
                        : "the program not executable (exit status 126); check its permissions");
  }
  return {};
}

void TeamProcesses::stop_all() {
  for (const Started& s : started_) {
    if (!s.ended && s.pid > 0) kill(s.pid, SIGINT);
  }
  const Nanos until = lockstep::wall_clock() + std::chrono::seconds(5);
  for (Started& s : started_) {
    while (!s.ended && s.pid > 0) {
      if (waitpid(s.pid, &s.status, WNOHANG) == s.pid) {
        s.ended = true;
      } else if (lockstep::wall_clock() > until) {
        std::fprintf(stderr, "canhil: `%s` (pid %d) did not end within 5 s of SIGINT; killed\n", s.command.c_str(),
                     s.pid);
        kill(s.pid, SIGKILL);
        waitpid(s.pid, &s.status, 0);
        s.ended = true;
      } else {
        const timespec a_while{0, 20'000'000};
        nanosleep(&a_while, nullptr);  // real: canhil's own waits never follow the board
      }
    }
  }
}

}  // namespace canhil::external
