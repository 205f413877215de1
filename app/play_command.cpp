// `canhil play TRACE --iface IFACE [--speed X] [--loop] [--map FROM=TO]`: a
// recorded bus put back on an interface, frame by frame at absolute deadlines
// from the start (can_nodes::PlaySchedule), at any speed: a team feeds a
// recorded robot's traffic to its handler. The summary says how late the
// sends were.
#include <atomic>
#include <fstream>
#include <map>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/can_nodes/trace_player.hpp"
#include "commands.hpp"
#include "stop_signals.hpp"

namespace canhil::app {
namespace {

std::vector<frames::LogEntry> read_trace(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError("cannot read " + path);
  std::vector<frames::LogEntry> out;
  std::string line, error;
  std::size_t n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    frames::LogEntry e;
    if (!frames::parse_log_line(line, e, &error)) {
      throw UsageError(path + ":" + std::to_string(n) + ": " + error + " (a candump -l log)");
    }
    out.push_back(std::move(e));
  }
  if (out.empty()) throw UsageError(path + " has no frames");
  return out;
}

}  // namespace

int run_play(Args& args, const std::optional<std::string>&) {
  const auto iface = args.option("--iface");
  const double speed = number_option(args, "--speed", 1);
  const bool loop = args.flag("--loop");
  std::map<std::string, std::string> map;
  while (auto m = args.option("--map")) {
    const auto eq = m->find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == m->size())
      throw UsageError("--map takes FROM=TO, e.g. vcan0=can0");
    map[m->substr(0, eq)] = m->substr(eq + 1);
  }
  if (!iface && map.empty()) throw UsageError("give --iface IFACE (where to play), or --map FROM=TO per interface");
  if (!(speed >= 0.001 && speed <= 1000)) throw UsageError("--speed takes 0.001..1000 (2: twice as fast)");
  if (args.positionals().size() != 2) throw UsageError("give one trace (a candump -l log)");
  const std::string path = args.positionals()[1];
  can_nodes::PlaySchedule schedule(read_trace(path), speed, loop);
  // One socket per interface played on.
  std::map<std::string, std::unique_ptr<can_nodes::SocketCanBus>> buses;
  const auto bus_for = [&](const std::string& recorded) -> can_nodes::SocketCanBus* {
    const auto m = map.find(recorded);
    if (m == map.end() && !iface) return nullptr;  // not mapped: not played
    const std::string& to = m != map.end() ? m->second : *iface;
    auto& bus = buses[to];
    if (!bus) {
      try {
        bus = can_nodes::SocketCanBus::open(to);
      } catch (const SetupError& e) {
        throw UsageError(e.what());
      }
    }
    return bus.get();
  };
  std::printf("canhil play: %s, %zu frame(s) over %.3f s, at %gx%s\n", path.c_str(), schedule.size(),
              to_seconds(schedule.span()), speed, loop ? ", looping (Ctrl-C ends)" : "");
  std::fflush(stdout);
  stop_on_signals();
  can_nodes::WallClock clock;
  const Nanos start = clock.now() + std::chrono::milliseconds(20);
  std::uint64_t sent = 0, dropped = 0, skipped = 0, passes = 0;
  Nanos worst_late{0};
  while (!g_stop) {
    const auto due = schedule.next();
    if (!due) break;
    passes = due->pass + 1;
    can_nodes::SocketCanBus* bus = bus_for(due->entry->iface);
    if (bus == nullptr) {
      ++skipped;
      continue;
    }
    const Nanos deadline = start + due->at;
    while (!g_stop && clock.now() < deadline) can_nodes::WallClock::sleep_until(deadline);
    if (g_stop) break;
    worst_late = std::max(worst_late, clock.now() - deadline);
    if (bus->send(due->entry->frame) == can_nodes::SendStatus::kOk) {
      ++sent;
    } else {
      ++dropped;
    }
  }
  std::printf(
      "canhil play: %s: %llu frame(s) sent in %llu pass(es), %llu not sent (interface down or queue full), "
      "%llu not mapped; worst lateness %.3f ms\n",
      g_stop ? "stopped" : "done", static_cast<unsigned long long>(sent), static_cast<unsigned long long>(passes),
      static_cast<unsigned long long>(dropped), static_cast<unsigned long long>(skipped), to_ms(worst_late));
  return g_stop ? 130 : (dropped > 0 ? 1 : 0);
}

}  // namespace canhil::app
