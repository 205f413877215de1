// Timed interfaces from canhil's side (bus.hpp): their wire settings, their
// controllers, restarts and faults on a running bus.
#include <linux/can.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "bus_internal.hpp"
#include "canhil/base/errno_text.hpp"
#include "canhil/frames/frame.hpp"
#include "canhil/userbus/bus.hpp"
#include "canhil/userbus/state.hpp"
#include "canhil/wire/wire_fault.hpp"

namespace canhil::userbus {
namespace {

Interface& interface_named(State& s, const std::string& name) {
  Interface* i = find_interface(s, name.c_str());
  if (i == nullptr) throw BusError("the bus has no interface " + name + " (`canhil bus list` lists them)");
  return *i;
}

void ask_about(const BusPaths& paths, const std::string& name, ControlRequest r, const char* what) {
  auto mapped = require_state(paths);
  r.ifindex = interface_named(mapped->state(), name).index;
  const int answer = ask_broker(paths, r);
  if (answer == -EINVAL)
    throw BusError(name + " has no wire: give it a bit rate first (canhil bus link " + name + " bitrate 500000)");
  if (answer == -EBUSY) throw BusError("no controller on " + name + " is bus-off: nothing to restart");
  if (answer == -ESRCH) throw BusError("that process has no controller on " + name);
  if (answer < 0) throw BusError(std::string("the broker refused to ") + what + ": " + errno_text(-answer));
}

}  // namespace

void set_link(const BusPaths& paths, const std::string& name, const LinkSettings& settings) {
  constexpr std::uint32_t kMaxRate = 20'000'000;
  const auto check_rate = [](std::optional<std::uint32_t> rate, const char* what) {
    if (rate && *rate != 0 && (*rate < 1000 || *rate > kMaxRate))
      throw BusError(std::string(what) + " takes 1000 to 20000000 bit/s (0: instant), got " + std::to_string(*rate));
  };
  check_rate(settings.bit_rate, "bitrate");
  check_rate(settings.data_bit_rate, "dbitrate");
  if (settings.restart_ms && (*settings.restart_ms < 0 || *settings.restart_ms > 3'600'000))
    throw BusError("restart-ms takes 0 (restart only on request) to 3600000 ms, got " +
                   std::to_string(*settings.restart_ms));
  if (settings.tx_queue && (*settings.tx_queue < 1 || *settings.tx_queue > 100000))
    throw BusError("txqueuelen takes 1 to 100000 frames, got " + std::to_string(*settings.tx_queue));
  auto mapped = require_state(paths);
  Interface& i = interface_named(mapped->state(), name);
  i.driven.store(0);  // the broker's own clock (a lockstep run's canhil drives its own)
  if (settings.bit_rate) i.bit_rate.store(*settings.bit_rate);
  if (settings.data_bit_rate) i.data_bit_rate.store(*settings.data_bit_rate);
  if (settings.restart_ms) i.restart_ms.store(*settings.restart_ms);
  if (settings.tx_queue) i.tx_queue.store(*settings.tx_queue);
  if (i.bit_rate.load() != 0 && i.data_bit_rate.load() != 0 && i.data_bit_rate.load() < i.bit_rate.load())
    i.data_bit_rate.store(0);  // a data phase slower than arbitration: none (as without BRS)
  const int answer = ask_broker(paths, kControlInterfacesChanged);
  if (answer < 0) throw BusError("the broker did not take " + name + "'s new settings: " + errno_text(-answer));
}

LinkSettings parse_link(const std::vector<std::string>& words) {
  LinkSettings out;
  for (std::size_t k = 0; k < words.size(); k += 2) {
    const std::string& key = words[k];
    if (k + 1 >= words.size()) throw BusError(key + " needs a value (e.g. bitrate 500000)");
    const std::string& text = words[k + 1];
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno != 0 || v < 0 || v > 0x7fffffff)
      throw BusError(key + " takes a whole number, got \"" + text + "\"");
    if (key == "bitrate") {
      out.bit_rate = static_cast<std::uint32_t>(v);
    } else if (key == "dbitrate") {
      out.data_bit_rate = static_cast<std::uint32_t>(v);
    } else if (key == "restart-ms") {
      out.restart_ms = static_cast<std::int32_t>(v);
    } else if (key == "txqueuelen") {
      out.tx_queue = static_cast<std::uint32_t>(v);
    } else {
      throw BusError("no link setting \"" + key +
                     "\" (bitrate, dbitrate, restart-ms, txqueuelen, or restart, up, down)");
    }
  }
  return out;
}

void restart_link(const BusPaths& paths, const std::string& name) {
  ask_about(paths, name, ControlRequest{kControlRestart}, "restart");
}

void add_bus_fault(const BusPaths& paths, const std::string& name, const wire::FaultRule& rule) {
  ControlRequest r{kControlFault};
  r.fault.kind = static_cast<std::uint32_t>(rule.kind);
  r.fault.from_ns = rule.from.count();
  r.fault.until_ns = rule.until == kNever ? -1 : rule.until.count();
  r.fault.rate = rule.rate;
  r.fault.has_id = rule.id ? 1 : 0;
  r.fault.id = rule.id.value_or(0);
  r.fault.pid = rule.controller ? static_cast<std::int32_t>(*rule.controller) : 0;
  r.fault.slot = -1;  // a process's controller (its sockets' own ones are canhil's nodes')
  r.fault.babble_id = rule.babble.id;
  ask_about(paths, name, r, "take the fault");
}

void clear_bus_faults(const BusPaths& paths, const std::string& name) {
  ask_about(paths, name, ControlRequest{kControlClearFaults}, "clear the faults");
}

std::string program_of(int pid) {
  char comm[64] = "?";
  const std::string path = "/proc/" + std::to_string(pid) + "/comm";
  if (FILE* f = std::fopen(path.c_str(), "r")) {
    if (std::fgets(comm, sizeof comm, f) != nullptr) comm[std::strcspn(comm, "\n")] = '\0';
    std::fclose(f);
  }
  return comm;
}

std::vector<ControllerView> controllers(const BusPaths& paths) {
  auto mapped = require_state(paths);
  State& s = mapped->state();
  std::vector<ControllerView> out;
  for (const Controller& c : s.controllers) {
    if (c.in_use.load(std::memory_order_acquire) == 0) continue;
    ControllerView v;
    v.pid = c.pid;
    v.socket = c.slot;
    v.program = program_of(c.pid);
    const Interface* i = find_interface(s, c.ifindex);
    v.interface = i != nullptr ? i->name : "index " + std::to_string(c.ifindex);
    v.state = frames::state_name(static_cast<frames::ControllerState>(std::min(c.state.load(), 3U)));
    v.tec = c.tec.load();
    v.rec = c.rec.load();
    v.sent = c.sent.load();
    v.received = c.received.load();
    v.errors = c.errors.load();
    v.bus_offs = c.bus_offs.load();
    v.restarts = c.restarts.load();
    v.refused = c.refused.load();
    v.queued = c.queued.load();
    out.push_back(v);
  }
  return out;
}

int controller_pid(const BusPaths& paths, const std::string& name, const std::string& who) {
  for (const ControllerView& v : controllers(paths)) {
    if (v.socket < 0 && v.interface == name && (std::to_string(v.pid) == who || v.program == who)) return v.pid;
  }
  return 0;
}

std::string wire_text(const Interface& i) {
  const std::uint32_t rate = i.bit_rate.load();
  if (rate == 0) return "  instant (no wire)";
  std::ostringstream out;
  const double wire_ns = static_cast<double>(i.wire_ns.load());
  out << "  bitrate " << rate;
  if (i.data_bit_rate.load() != 0) out << " dbitrate " << i.data_bit_rate.load();
  const std::int32_t restart = i.restart_ms.load();
  out << "  restart-ms " << restart << (restart == 0 ? " (on request)" : "") << "  txqueuelen " << i.tx_queue.load();
  char load[32];
  std::snprintf(load, sizeof load, "%.1f", wire_ns > 0 ? 100.0 * static_cast<double>(i.busy_ns.load()) / wire_ns : 0.0);
  out << "  load " << load << " %  error frames " << i.error_frames.load();
  return out.str();
}

std::string controllers_text(const BusPaths& paths) {
  std::ostringstream out;
  for (const ControllerView& v : controllers(paths)) {
    out << "  controller pid " << v.pid << " (" << v.program << ")"
        << (v.socket >= 0 ? "  socket " + std::to_string(v.socket) : std::string()) << "  " << v.interface << "  "
        << v.state << "  tec " << v.tec << " rec " << v.rec << "  sent " << v.sent << "  received " << v.received
        << "  errors " << v.errors << "  bus-off " << v.bus_offs << "  restarts " << v.restarts << "  queued "
        << v.queued << "  ENOBUFS " << v.refused << '\n';
  }
  return out.str();
}

}  // namespace canhil::userbus
