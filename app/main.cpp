// canhil — command-line entry point. The only place that reads the wall clock.
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "args.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/frames/dbc.hpp"
#include "canhil/physics/config.hpp"
#include "commands.hpp"

namespace {

constexpr const char* kUsage = R"(canhil — hardware-in-the-loop emulator for a CAMBADA-style robot's CAN network

usage:
  canhil frames list [--json]                 messages, ids, periods, kinds
  canhil frames encode MESSAGE SIGNAL=VALUE...  print the frame (candump compact form)
  canhil frames decode FRAME... [--json]      decode frames like 131#F401000000000000
  canhil dump IFACE [--count N] [--seconds S] [--json]
                                              live, decoded, with kernel timestamps
  canhil dump --log FILE [--json]             decode a candump log file (- for stdin)
  canhil nodes --iface IFACE [--config WORLD.toml] [--duration S] [--ec-ms 10] [--bit-rate 1000000] [--quiet]
                                              one robot's emulated nodes with physics, real time
  canhil run --virtual-time [--config SCENARIO.toml] [--duration S] [--seed N] [--fault RULE]...
             [--trace FILE] [--world-log FILE.csv] [--world-log-period 0.05] [--kick-power P] [--quiet]
             [--save-world FILE] [--restore-world FILE]
                                              the whole loop in virtual time: nodes, physics, vision,
                                              the reference handler and agent per robot; a candump trace
                                              of every bus; faults like drop:M4_1:0.1 (docs/faults.md);
                                              scenarios in emulator/scenarios/
  canhil run [--config SCENARIO.toml] [--duration S] [--seed N] [--fault RULE]... [--bit-rate B]
             [--rx-buffer-kb 1024] [--priority 40] [--save-world FILE] [--restore-world FILE] [--quiet]
                                              real time: every robot's nodes on its interface (vcan0, ...),
                                              vision into its agent's RTDB; run your handler and agent
                                              (or canhil-hwcomm, canhil-agent) with AGENT=N next to it
  canhil bench [--part virtual,jitter,vcan] [--seconds 60] [--config S] [--iface vcan0] [--rt-seconds 10]
               [--frames 200000] [--priority 40]
                                              the figures against their targets: the five-robot real-time
                                              factor in virtual time; release jitter against a bare
                                              clock_nanosleep loop; lossless vcan rate against cangen -g 0
  canhil timing SOURCE [--json] [--svg FILE] [--ec-ms 10] [--bit-rate 1000000] [--slack-us 0] [--seconds S]
                                              periods, jitter, missing/late frames, FTT compliance and
                                              bus load of a candump log or a live interface; exit 1 if violated
  canhil rtdb list                            agents and items of the RTDB on this machine, with ages
  canhil rtdb dump|watch ITEM [--agent A] [--from B]
                                              one item (known types decoded, others in hex); watch repeats
  canhil rtdb replicate [--period-ms 100] [--delay-ms 0] [--loss 0] [--seed 1]
                                              copy shared items between agents (the team's wireless)
  canhil experiment NAME [--json] [--svg FILE] [--config WORLD.toml] [options]
                                              physics calibration: ball-drop [--height M],
                                              ball-roll [--speed MPS], kick [--low|--high] [--power P],
                                              drive [--vx --vy --va], tour; exit 1 if a target is missed;
                                              vision [--robot N] [--noise M] [--svg FILE]: one frame, drawn

common options:
  --dbc FILE    use another message set (default: the shipped canhil.dbc; CANHIL_DBC also works)
  --help        this text
  --version     canhil's version

exit status: 0 ok, 1 the input had problems (unknown ids, bad lengths), 2 usage or set-up error.
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> words(argv + 1, argv + argc);
  canhil::app::Args args(words);
  try {
    if (words.empty() || args.flag("--help") || args.flag("-h")) {
      std::fputs(kUsage, words.empty() ? stderr : stdout);
      return words.empty() ? 2 : 0;
    }
    if (args.flag("--version")) {
      std::puts("canhil " CANHIL_VERSION);
      return 0;
    }
    const auto dbc = args.option("--dbc");
    const std::string command = args.command();
    if (command.empty()) throw canhil::app::UsageError("no command given");
    if (command == "frames") return canhil::app::run_frames(args, dbc);
    if (command == "dump") return canhil::app::run_dump(args, dbc);
    if (command == "experiment") return canhil::app::run_experiment(args);
    if (command == "nodes") return canhil::app::run_nodes(args, dbc);
    if (command == "rtdb") return canhil::app::run_rtdb(args);
    if (command == "timing") return canhil::app::run_timing(args, dbc);
    if (command == "run") return canhil::app::run_run(args, dbc);
    if (command == "bench") return canhil::app::run_bench(args, dbc);
    throw canhil::app::UsageError("unknown command \"" + command + "\"");
  } catch (const canhil::app::UsageError& e) {
    std::fprintf(stderr, "canhil: %s\n\n%s", e.what(), kUsage);
    return 2;
  } catch (const canhil::frames::DbcError& e) {
    std::fprintf(stderr, "canhil: %s\n", e.what());
    return 2;
  } catch (const canhil::physics::ConfigError& e) {
    std::fprintf(stderr, "canhil: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "canhil: %s\n", e.what());
    return 2;
  } catch (const canhil::can_nodes::SetupError& e) {
    std::fprintf(stderr, "canhil: %s\n", e.what());
    return 2;
  }
}
