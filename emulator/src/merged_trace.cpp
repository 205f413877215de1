#include "merged_trace.hpp"

#include <algorithm>

#include "canhil/frames/candump.hpp"

namespace canhil::emulator {

std::string merged_trace(const std::vector<std::vector<frames::TimedFrame>>& per_bus,
                         const std::vector<std::string>& interface_names) {
  struct Line {
    Nanos time;
    std::size_t bus;
    std::size_t order;
  };
  std::vector<Line> lines;
  for (std::size_t r = 0; r < per_bus.size(); ++r) {
    for (std::size_t i = 0; i < per_bus[r].size(); ++i) lines.push_back({per_bus[r][i].time, r, i});
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.time != b.time ? a.time < b.time : a.bus < b.bus; });
  std::string out;
  for (const Line& l : lines) {
    out += frames::format_log_line(l.time, interface_names.at(l.bus), per_bus[l.bus][l.order].frame);
    out += '\n';
  }
  return out;
}

}  // namespace canhil::emulator
