// canhil — command-line entry point. The only place that reads the wall clock.
//
// Each command has its own usage text: a mistake prints the error, that
// command's usage and a pointer to `canhil help`; `canhil COMMAND --help` and
// `canhil help COMMAND` print one command's usage, `canhil help` all of them.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "args.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/external/private_rtdb.hpp"
#include "canhil/physics/solver_health.hpp"
#include "canhil/userbus/bus.hpp"
#include "commands.hpp"
#include "stop_signals.hpp"

namespace {

using canhil::app::Args;
using DbcOption = std::optional<std::string>;

struct Command {
  const char* name;
  const char* summary;  ///< one line for the overview
  const char* usage;    ///< the command's own usage, options and examples
  int (*run)(Args&, const DbcOption&);
};

int run_experiment(Args& args, const DbcOption&) { return canhil::app::run_experiment(args); }
int run_rtdb(Args& args, const DbcOption&) { return canhil::app::run_rtdb(args); }
int run_pman(Args& args, const DbcOption&) { return canhil::app::run_pman(args); }

const Command kCommands[] = {
    {"frames", "the message set: list, encode and decode frames",
     R"(  canhil frames list [--json]                 messages, ids, periods, kinds
  canhil frames encode MESSAGE SIGNAL=VALUE...  print the frame (candump compact form)
  canhil frames decode FRAME... [--json]      decode frames like 131#F401000000000000
)",
     canhil::app::run_frames},
    {"dump", "decode a live interface or a candump log",
     R"(  canhil dump IFACE [--count N] [--seconds S] [--json]
                                              live, decoded, with kernel timestamps
  canhil dump --log FILE [--head N] [--json]  decode a candump log file (- for stdin); --head N
                                              prints the first N frames, then the summary
)",
     canhil::app::run_dump},
    {"nodes", "one robot's emulated nodes with physics on an interface, real time",
     R"(  canhil nodes --iface IFACE [--config WORLD.toml] [--emulate NODE,...] [--duration S] [--ec-ms 10]
               [--bit-rate 1000000] [--quiet]
                                              one robot's emulated nodes with physics, real time;
                                              --emulate names the nodes canhil plays (default all),
                                              the others being real boards on the bus
)",
     canhil::app::run_nodes},
    {"run", "a scenario: the whole loop in virtual time, or real time on SocketCAN",
     R"(  canhil run --virtual-time [--config SCENARIO.toml] [--duration S] [--seed N] [--fault RULE]...
             [--trace FILE] [--world-log FILE.csv] [--world-log-period 0.05] [--kick-power P] [--quiet]
             [--save-world FILE] [--restore-world FILE] [--speed max|X] [--paused]
                                              the whole loop in virtual time: nodes, physics, vision,
                                              the reference handler and agent per robot; a candump trace
                                              of every bus; faults like drop:M4_1:0.1 (docs/faults.md);
                                              scenarios in emulator/scenarios/
  canhil run --external [--process "CMD"]... [--answer-limit 1] [--wait-for N] [--config SCENARIO.toml]
             [--duration S] [--seed N] [--fault RULE]... [--trace FILE] [--world-log FILE.csv] [--quiet]
                                              virtual time with the team's own handler and agent as
                                              processes in lockstep (the time shim preloaded): the
                                              scenario's [external] processes or --process, started per
                                              robot ({agent}, {iface}); without any, waits for N started
                                              by hand (docs/lockstep.md); exit 3 when one stops answering
  canhil run [--config SCENARIO.toml] [--duration S] [--seed N] [--fault RULE]... [--bit-rate B]
             [--rx-buffer-kb 1024] [--priority 40] [--save-world FILE] [--restore-world FILE] [--quiet]
             [--control PATH | --no-control] [--rtdb-lib LIB --rtdb-items RTDB_USER_H --rtdb-ini RTDB_INI]
             [--layout cambada|canhil|FILE] [--pman-lib LIB | --no-pman]
                                              real time: every robot's nodes on its interface (vcan0, ...),
                                              vision into its agent's RTDB (canhil's, or the team's library
                                              in the team's layout), each agent woken through PMan; run
                                              your handler and agent (or canhil-hwcomm, canhil-agent) with
                                              AGENT=N next to it (docs/own-software.md)
  --bit-rate B                                 the buses on a timed wire at B bit/s (default: [bus] bit_rate,
                                              else the DBC's Baudrate): frames take their bits and lose
                                              arbitration, controllers go bus-off and restart, faults such
                                              as busoff:laptop act on the wire; 0 is instant, as vcan
                                              (virtual time, lockstep, the user-space bus: docs/wire.md)
  viewer (every run but --external): [--view-port 8765] [--view-listen 127.0.0.1] [--no-view]
             [--view-hold S] [--save-dir canhil-saves]
                                              a web page at http://127.0.0.1:8765/ shows the world and
                                              changes it: drag robots and the ball, pause, step, speed,
                                              coach, faults, saves (docs/viewer.md)
)",
     canhil::app::run_run},
    {"match", "whole matches of two teams in virtual time, with a table of results",
     R"(  canhil match SCENARIO.toml [--halves 2] [--half-minutes 10] [--seeds 1..200 | --repeat 1 [--seed N]]
               [--jobs CORES] [--records FILE.jsonl | --no-records] [--json] [--quiet] [--logs DIR] [--bit-rate B]
                                              two teams ([[teams]]) play whole matches in virtual time,
                                              ends changed at half time, the referee on, --jobs at a time
                                              (worker processes); per match and in total: score,
                                              possession, shots, kicks, faults and FTT violations per
                                              team; one record per match appended to FILE
                                              (match-records.jsonl); --logs DIR keeps every half's
                                              trace and world log (docs/teams.md)
  canhil match --report RECORDS.jsonl... [--json] [--svg FILE]
                                              records from any files merged: wins, draws, losses, goal
                                              difference with its 95 % interval, win rate (Wilson),
                                              significance (sign test), the figures per team
  canhil match SCENARIO.toml --external [--process "COMMAND"]... [--logs DIR] [--answer-limit S] ...
                                              the teams' own processes play each half, in lockstep, started
                                              afresh per half from [teams.external] (else [external]) or
                                              --process; their output to DIR or stderr (needs the robots'
                                              interfaces, e.g. vcan0..vcan9); one match at a time, or
                                              --jobs N, each on a user-space bus and in an IPC namespace
                                              of its own
)",
     canhil::app::run_match},
    {"test", "a team's regression tests as files: expectations, verdicts, JUnit XML",
     R"(  canhil test FILE.toml... [--junit FILE.xml] [--jobs N] [--artifacts DIR] [--external] [--quiet]
                                              each test file's scenario in virtual time with its events
                                              (faults, coach orders, a ball moved, a set-pose); a line per
                                              expectation on the bus, the world and the RTDB with its
                                              verdict and measure; exit 0 only if all pass; --junit for
                                              the CI, --artifacts DIR keeps each file's trace, world log
                                              and verdicts; --external: the scenario's [external]
                                              processes (your handler and agent) in lockstep, their
                                              logs with the artifacts (docs/testing-your-software.md)
)",
     canhil::app::run_test},
    {"view", "a recorded run (world log and trace) in the web viewer, with a timeline",
     R"(  canhil view WORLD_LOG.csv [--trace FILE] [--config SCENARIO.toml] [--view-port 8765]
             [--view-listen 127.0.0.1] [--duration S]
                                              serves the viewer on a world log (canhil run --world-log):
                                              play, pause, scrub, speed, jump to goals and kicks; the
                                              trace's frames around the cursor, decoded (docs/viewer.md)
)",
     canhil::app::run_view},
    {"play", "a recorded bus put back on an interface, at any speed",
     R"(  canhil play TRACE --iface IFACE [--speed 1] [--loop] [--map FROM=TO]...
                                              sends a candump log's frames on IFACE, paced from their
                                              timestamps with absolute deadlines, at --speed (0.5: half,
                                              2: twice as fast); --loop starts again at the end; frames of
                                              every interface in the log go to IFACE unless --map says
)",
     canhil::app::run_play},
    {"bench", "the performance figures against their targets",
     R"(  canhil bench [--part virtual,view,match,jobs,analyse,wire,jitter,vcan,external] [--seconds 60] [--config S] [--iface vcan0]
               [--rt-seconds 10] [--frames 200000] [--priority 40] [--cpu 0]
                                              the figures against their targets: the five-robot real-time
                                              factor in virtual time; the same with a page on the viewer
                                              (keeps >= 90 %); a ten-robot match half and five
                                              robots on one core (>= 80x and 180x; physics
                                              alone for scale); timing --analyse of a 200-message
                                              set (<= 50 ms); the five robots on timed wires at
                                              1 Mbit/s against instant buses (>= 0.9x);
                                              match halves per minute, --jobs 2
                                              against --jobs 1 (>= 1.8x); release jitter against a bare
                                              clock_nanosleep loop; lossless vcan rate against cangen -g 0;
                                              the one-robot factor with the reference handler and agent as
                                              processes in lockstep (on core --cpu, -1: any), next to
                                              in-process
)",
     canhil::app::run_bench},
    {"timing", "periods, jitter and FTT compliance of a log or a live interface",
     R"(  canhil timing SOURCE [--json] [--svg FILE] [--ec-ms 10] [--bit-rate 1000000] [--slack-us 0] [--seconds S]
                [--allow-empty] [--stamps start|end]
                                              periods, jitter, missing/late frames, FTT compliance and
                                              bus load of a candump log or a live interface; exit 1 if
                                              violated, or if the capture has no frames, no trigger
                                              message or is shorter than the longest period (unless
                                              --allow-empty)
  canhil timing --analyse [TRACE] [--json] [--svg FILE] [--ec-ms MS] [--bit-rate BPS] [--sync-window-us US]
                [--guard-us 20] [--add "NAME ID DLC PERIOD_MS sync|async"]... [--copies NAME]...
                [--no-what-if] [--slack-us 0] [--stamps start|end]
                                              what the message set allows, from the DBC: frame times,
                                              the FTT master's schedule and its test, every sporadic
                                              message's worst-case response (native CAN's without a
                                              trigger message), the lowest bit rate, the shortest EC
                                              and how many more copies fit; with TRACE every observation
                                              next to its bound; exit 1 if a message misses or an
                                              observation passes its bound
)",
     canhil::app::run_timing},
    {"rtdb", "the real-time database on this machine",
     R"(  canhil rtdb list                            agents and items of the RTDB on this machine, with ages
  canhil rtdb dump|watch ITEM [--agent A] [--from B]
                                              one item (known types decoded, others in hex); watch repeats
  canhil rtdb replicate [--period-ms 100] [--delay-ms 0] [--loss 0] [--seed 1]
                                              copy shared items between agents (the team's wireless)
)",
     run_rtdb},
    {"coach", "the base station's orders to a running canhil run",
     R"(  canhil coach STATE [--control PATH]         the game state for every robot: stop, start, our_kickoff,
                                              their_kickoff, drop_ball, ... (emulator/coach.hpp)
  canhil coach --robot N [--running yes|no] [--role ROLE]
                                              one robot's orders
  canhil coach status                         what the coach says now
                                              (PATH: the run's control socket, as canhil run prints it)
)",
     canhil::app::run_coach},
    {"pman", "the robots' PMan tables: who is registered, attached and woken",
     R"(  canhil pman list                            every robot's PMan table (keys 0x9011 + 2 x agent): its
                                              processes, their pids, states and activations, read
                                              without attaching (canhil run's, or the team's master's)
)",
     run_pman},
    {"bus", "a user-space CAN bus for machines whose kernel has no CAN",
     R"(  canhil bus up [IFACE...] [broker options]   start the bus (if none runs) with interfaces (default vcan0)
  canhil bus exec [--ifaces vcan0,...] [broker options] -- COMMAND...
                                              run COMMAND and everything it starts on the bus (preloading
                                              libcanhil-bus.so), creating the interfaces it names; a bus
                                              this starts ends with COMMAND
  canhil bus list                             interfaces, sockets and controllers, with their counters
  canhil bus down [IFACE...]                  remove interfaces, or stop the whole bus
  canhil bus link IFACE up|down|restart       bring an interface up or down, restart its bus-off controllers
  canhil bus link IFACE bitrate N [dbitrate N] [restart-ms N] [txqueuelen N]
                                              give it a wire (0: instant), as ip link's CAN settings
  canhil bus fault IFACE RULE...|clear        wire faults from now on (ber, error, noack, stuck, babble,
                                              cut, busoff; a node is a program on the bus: docs/wire.md)
  canhil bus preload                          print the path of libcanhil-bus.so (for LD_PRELOAD)
                                              (docs/vcan.md: the bus, its limits, how to choose)
  broker options, for a bus that up or exec starts:
    --backlog 4096                            frames that wait in the bus for a receiver whose buffer
                                              is full, while the bus goes on for the others
    --grace-ms 10                             how long a receiver whose backlog is full may read nothing
                                              while it could, before frames drop for it (0: at once)
    --patience-ms 250                         the longest the bus waits for one full receiver in all
    --rt-priority 45                          the broker's SCHED_FIFO priority (0: normal scheduler)
    --bit-rate 0                              up, exec: the interfaces' bit rate (0: instant, no wire)
)",
     canhil::app::run_bus},
    {"experiment", "physics calibration experiments and a vision frame",
     R"(  canhil experiment NAME [--json] [--svg FILE] [--config WORLD.toml] [options]
                                              physics calibration: ball-drop [--height M],
                                              ball-roll [--speed MPS], kick [--low|--high] [--power P],
                                              drive [--vx --vy --va], tour; exit 1 if a target is missed;
                                              vision [--robot N] [--noise M] [--svg FILE]: one frame, drawn
)",
     run_experiment},
};

constexpr const char* kHead = "canhil — hardware-in-the-loop emulator for a CAMBADA-style robot's CAN network\n";
constexpr const char* kCommon = R"(
common options:
  --dbc FILE    use another message set (default: the shipped canhil.dbc; CANHIL_DBC also works)
  --help        the usage of the command (canhil COMMAND --help), or of all
  --version     canhil's version

exit status: 0 ok, 1 the input had problems (unknown ids, bad lengths), 2 usage or set-up error.
)";

const Command* find_command(const std::string& name) {
  for (const Command& c : kCommands) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

void print_all(FILE* out) {
  std::fprintf(out, "%s\ncommands:\n", kHead);
  for (const Command& c : kCommands) std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(out, "\nusage:\n");
  for (const Command& c : kCommands) std::fputs(c.usage, out);
  std::fputs(kCommon, out);
}

void print_one(FILE* out, const Command& c) {
  std::fprintf(out, "usage:\n%s", c.usage);
  std::fprintf(out, "(--dbc FILE picks another message set; `canhil help` lists every command)\n");
}

// `canhil help [COMMAND]`.
int run_help(const std::vector<std::string>& words) {
  if (words.size() <= 1) {
    print_all(stdout);
    return 0;
  }
  if (const Command* c = find_command(words[1])) {
    print_one(stdout, *c);
    return 0;
  }
  std::fprintf(stderr, "canhil: no command \"%s\"; `canhil help` lists them\n", words[1].c_str());
  return 2;
}

// A mistake: the message, then what the command takes (or the command list).
int usage_error(const char* what, const Command* command) {
  std::fprintf(stderr, "canhil: %s\n\n", what);
  if (command != nullptr) {
    print_one(stderr, *command);
  } else {
    std::fprintf(stderr, "commands:");
    for (const Command& c : kCommands) std::fprintf(stderr, " %s", c.name);
    std::fprintf(stderr, "\n`canhil help` shows how to use each, `canhil COMMAND --help` one of them\n");
  }
  return 2;
}

}  // namespace

namespace {

// The command named on the line, its exit status.
int run_command_line(int argc, char** argv) {
  std::vector<std::string> words(argv + 1, argv + argc);
  Args args(words);
  words.resize(
      std::min(words.size(), static_cast<std::size_t>(std::find(words.begin(), words.end(), "--") - words.begin())));
  const Command* command = nullptr;
  try {
    if (words.empty()) return usage_error("no command given", nullptr);
    if (args.flag("--version")) {
      std::puts("canhil " CANHIL_VERSION);
      return 0;
    }
    const bool help = args.flag("--help") || args.flag("-h");
    const auto dbc = args.option("--dbc");  // before the command: it may stand in front of it
    const std::string name = args.command();
    if (name == "help") return run_help(args.positionals());
    command = find_command(name);
    if (help) {
      if (command != nullptr) {
        print_one(stdout, *command);
      } else {
        print_all(stdout);
      }
      return 0;
    }
    if (name.empty()) return usage_error("no command given", nullptr);
    if (command == nullptr) return usage_error(("unknown command \"" + name + "\"").c_str(), nullptr);
    // The commands that open SocketCAN interfaces find the user-space bus by themselves.
    for (const char* can : {"run", "nodes", "dump", "timing", "play", "bench", "match", "test"}) {
      if (name == can) canhil::userbus::join_bus_if_needed(argv);
    }
    return command->run(args, dbc);
  } catch (const canhil::app::UsageError& e) {
    return usage_error(e.what(), command);
  } catch (const canhil::SetupError& e) {  // every other mistake a user can fix says what to do
    std::fprintf(stderr, "canhil: %s\n", e.what());
    return 2;
  } catch (const canhil::physics::SolverError& e) {  // ODE stopped: the world cannot be simulated further
    std::fprintf(stderr, "canhil: the physics stopped: %s (docs/physics.md, solver health)\n", e.what());
    return 4;
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int status = run_command_line(argc, argv);
  canhil::external::release_private_rtdb_keys();
  canhil::app::end_by_sigpipe_if_seen();  // a command whose output's reader left ends by SIGPIPE
  return status;
}
