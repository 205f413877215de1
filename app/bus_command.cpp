// `canhil bus`: the user-space CAN bus (userbus/) from the command line.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "args.hpp"
#include "canhil/can_nodes/wire_faults.hpp"
#include "canhil/frames/messages.hpp"
#include "canhil/userbus/bus.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"

namespace canhil::app {
namespace {

namespace ub = canhil::userbus;

/// The broker's options from --backlog, --grace-ms, --patience-ms and --rt-priority.
ub::BrokerOptions broker_options(Args& args) {
  ub::BrokerOptions options;
  const auto milliseconds = [&args](const std::string& name, std::uint32_t fallback_us) {
    const auto ms = optional_number(args, name);
    if (!ms) return fallback_us;
    if (*ms < 0 || *ms > 10000) throw UsageError(name + " takes 0 to 10000 milliseconds, got " + std::to_string(*ms));
    return static_cast<std::uint32_t>(*ms * 1000.0);
  };
  options.grace_us = milliseconds("--grace-ms", options.grace_us);
  options.patience_us = milliseconds("--patience-ms", options.patience_us);
  if (const auto n = optional_number(args, "--backlog")) {
    if (*n < 1 || *n > 1000000 || *n != static_cast<std::uint32_t>(*n))
      throw UsageError("--backlog takes 1 to 1000000 frames, got " + std::to_string(*n));
    options.backlog_frames = static_cast<std::uint32_t>(*n);
  }
  if (const auto p = optional_number(args, "--rt-priority")) {
    if (*p < 0 || *p > 99 || *p != static_cast<int>(*p))
      throw UsageError("--rt-priority takes a SCHED_FIFO priority 1..99, or 0 for the normal scheduler");
    options.rt_priority = static_cast<int>(*p);
  }
  return options;
}

/// --bit-rate on `bus up` and `bus exec`: the interfaces' wire (docs/wire.md).
void set_bit_rate(const std::optional<std::string>& rate, const ub::BusPaths& paths,
                  const std::vector<std::string>& names) {
  if (!rate) return;
  const ub::LinkSettings link = ub::parse_link({"bitrate", *rate});
  for (const std::string& n : names) ub::set_link(paths, n, link);
}

/// `canhil bus fault IFACE RULE... | clear`: the fault language's wire rules
/// (docs/faults.md) on a running bus, from now on; a node is a process.
int bus_fault(const std::vector<std::string>& words, const ub::BusPaths& paths, const std::optional<std::string>& dbc) {
  if (words.size() < 4) throw UsageError("canhil bus fault IFACE RULE... | clear, e.g. ber:*:1e-5, busoff:cangen");
  const std::string& iface = words[2];
  if (words[3] == "clear") {
    ub::clear_bus_faults(paths, iface);
    return 0;
  }
  const auto set = frames::MessageSet::create(load_chosen_dbc(dbc));
  for (std::size_t k = 3; k < words.size(); ++k) {
    const can_nodes::FaultRule rule = can_nodes::parse_fault(words[k]);
    const auto pid_of = [&](std::string_view who) -> std::optional<wire::ControllerId> {
      const int pid = ub::controller_pid(paths, iface, std::string(who));
      return pid > 0 ? std::optional<wire::ControllerId>(static_cast<wire::ControllerId>(pid)) : std::nullopt;
    };
    const auto rules = can_nodes::wire_rules({rule}, *set, pid_of);
    if (rules.empty())
      throw UsageError("fault '" + rule.text + "': a running bus takes ber, error, noack, stuck, babble, cut and " +
                       "busoff, aimed at *, a message of the DBC or a program on " + iface + " (canhil bus list)");
    ub::add_bus_fault(paths, iface, rules.front());
    std::printf("canhil bus: %s on %s\n", rule.text.c_str(), iface.c_str());
  }
  return 0;
}

/// Starts a broker when none runs; true when this call started it.
bool ensure_bus(const ub::BusPaths& paths, ub::BrokerOptions options, bool detached) {
  if (ub::broker_alive(paths)) return false;
  if (detached) {
    ub::start_broker_detached(paths, options);  // `bus up`: the broker outlives this command
    return true;
  }
  ub::start_broker(paths, options);
  return true;
}

int bus_up(Args& args, const ub::BusPaths& paths) {
  ub::BrokerOptions options = broker_options(args);
  const auto rate = args.option("--bit-rate");
  std::vector<std::string> names = args.positionals();
  names.erase(names.begin(), names.begin() + 2);  // "bus up"
  if (names.empty()) names.push_back("vcan0");
  for (const std::string& n : names) ub::check_interface_name(n);
  const bool started = ensure_bus(paths, options, true);
  ub::add_interfaces(paths, names);
  set_bit_rate(rate, paths, names);
  std::printf("canhil bus: %s at %s\n", started ? "started" : "running", paths.folder.c_str());
  std::fputs(ub::describe(paths).c_str(), stdout);
  std::printf("programs reach it with LD_PRELOAD=%s, or: canhil bus exec -- COMMAND\n", ub::find_preload().c_str());
  return 0;
}

int bus_exec(Args& args, const ub::BusPaths& paths) {
  ub::BrokerOptions options = broker_options(args);
  const auto ifaces = args.option("--ifaces");
  const auto rate = args.option("--bit-rate");
  std::vector<std::string> rest = args.positionals();
  if (rest.size() > 2) throw UsageError("`canhil bus exec` takes the command after --, not \"" + rest[2] + "\"");
  const std::vector<std::string>& command = args.after_dashes();
  if (command.empty()) throw UsageError("`canhil bus exec` needs a command after --: canhil bus exec -- candump vcan0");
  std::vector<std::string> names;
  std::istringstream list(ifaces.value_or("vcan0"));
  for (std::string one; std::getline(list, one, ',');) {
    if (!one.empty()) names.push_back(one);
  }
  for (const std::string& n : names) ub::check_interface_name(n);
  ub::find_preload();  // before a bus is started: none, no command

  options.owner = getpid();
  const bool started = ensure_bus(paths, options, false);
  const std::vector<std::string> created = ub::add_interfaces(paths, names);
  set_bit_rate(rate, paths, names);
  if (started)
    std::fprintf(stderr, "canhil bus exec: a bus of its own, its broker at %s\n", ub::broker_scheduling(paths).c_str());
  const std::vector<ub::InterfaceCounts> counts_before = ub::interface_counts(paths);

  const int status = ub::run_on_bus(paths, command);
  std::fputs(ub::exec_report(paths, names, counts_before, started).c_str(), stderr);
  if (started) {
    ub::stop_broker(paths);
  } else if (!created.empty()) {
    ub::remove_interfaces(paths, created);
  }
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
}

}  // namespace

int run_bus(Args& args, const std::optional<std::string>& dbc) {
  try {
    const ub::BusPaths paths = ub::BusPaths::current();
    const std::string what = args.word_after("bus");
    if (what == "up") return bus_up(args, paths);
    if (what == "exec") return bus_exec(args, paths);
    std::vector<std::string> words = args.positionals();
    if (what == "preload") {
      std::puts(ub::find_preload().c_str());
      return 0;
    }
    if (what == "list") {
      if (!ub::broker_alive(paths)) {
        std::printf("no user-space CAN bus runs at %s (start one: canhil bus up vcan0)\n", paths.folder.c_str());
        return 0;
      }
      std::fputs(ub::describe(paths).c_str(), stdout);
      return 0;
    }
    if (what == "down") {
      words.erase(words.begin(), words.begin() + 2);
      if (words.empty()) {
        const bool was = ub::broker_alive(paths);
        ub::stop_broker(paths);
        std::printf("canhil bus: %s\n", was ? "stopped" : "no bus was running");
      } else {
        ub::remove_interfaces(paths, words);
      }
      return 0;
    }
    if (what == "link") {
      if (words.size() < 4)
        throw UsageError("canhil bus link IFACE up|down|restart|bitrate N [dbitrate N] [restart-ms N] [txqueuelen N]");
      if (words[3] == "up" || words[3] == "down") {
        ub::set_interface_up(paths, words[2], words[3] == "up");
      } else if (words[3] == "restart") {
        ub::restart_link(paths, words[2]);
      } else {
        ub::set_link(paths, words[2], ub::parse_link({words.begin() + 3, words.end()}));
      }
      return 0;
    }
    if (what == "fault") return bus_fault(words, paths, dbc);
    throw UsageError(what.empty()
                         ? "canhil bus takes up, exec, list, down, link, fault or preload"
                         : "canhil bus: no subcommand \"" + what + "\" (up, exec, list, down, link, fault, preload)");
  } catch (const ub::BusError& e) {
    throw SetupError(e.what());
  }
}

}  // namespace canhil::app
