#include "canhil/wire/report.hpp"

#include <cstdio>

namespace canhil::wire {

std::string report(const WireBus& bus, const std::string& indent) {
  const WireStats& s = bus.stats();
  char line[256];
  std::snprintf(line, sizeof line, "%son the wire at %u kbit/s: %.1f %% load, %llu frames, %llu failed by errors\n",
                indent.c_str(), bus.config().bit_rate / 1000, 100 * s.load(), static_cast<unsigned long long>(s.frames),
                static_cast<unsigned long long>(s.error_frames));
  std::string out = line;
  for (ControllerId c = 0; c < bus.controllers(); ++c) {
    const ControllerStatus k = bus.status(c);
    if (k.errors == 0 && k.bus_offs == 0 && k.refused == 0 && k.state == ControllerState::kErrorActive) continue;
    std::snprintf(
        line, sizeof line,
        "%s  %-10s %s, TEC %u, REC %u; %llu errors seen, %llu bus-off, %llu restarts, %llu frames refused%s\n",
        indent.c_str(), k.name.c_str(), state_name(k.state), unsigned{k.tec}, unsigned{k.rec},
        static_cast<unsigned long long>(k.errors), static_cast<unsigned long long>(k.bus_offs),
        static_cast<unsigned long long>(k.restarts), static_cast<unsigned long long>(k.refused),
        k.connected ? "" : " (off the bus)");
    out += line;
  }
  return out;
}

}  // namespace canhil::wire
