#include "canhil/emulator/bus_watch.hpp"

#include <algorithm>
#include <cstring>

#include "canhil/frames/candump.hpp"

namespace canhil::emulator {
namespace {

constexpr std::uint64_t kHashStart = 0xcbf29ce484222325ULL;  // the start of every hash

// One 64-bit word into the hash: xor, an odd multiplier (2^64 / golden ratio),
// the high half folded down. Three words a frame: a few cycles, not one
// multiply a byte.
void mix(std::uint64_t& h, std::uint64_t v) noexcept {
  h ^= v;
  h *= 0x9E3779B97F4A7C15ULL;
  h ^= h >> 32;
}

}  // namespace

timing::TimingAnalyzer ftt_checker(const SessionOptions& options) {
  timing::TimingConfig config;
  config.ftt = options.ftt;
  config.violations_only = true;
  return {options.messages, config};
}

BusWatch::BusWatch(const Session& session, Options options) : session_(session.options()), options_(options) {
  for (std::size_t r = 0; r < session.robot_count(); ++r) interfaces_.push_back(session.rig(r).interface);
  counts_.assign(interfaces_.size(), 0);
  hashes_.assign(interfaces_.size(), kHashStart);
  if (options_.record_trace) recorded_.resize(interfaces_.size());
  if (options_.check_timing) {
    for (std::size_t r = 0; r < interfaces_.size(); ++r) checkers_.push_back(ftt_checker(session_));
  }
}

void BusWatch::add(std::size_t robot, const frames::TimedFrame& frame) {
  ++counts_[robot];
  std::uint64_t& h = hashes_[robot];
  const frames::CanFrame& f = frame.frame;
  mix(h, static_cast<std::uint64_t>(frame.time.count()));
  mix(h, (std::uint64_t{f.id} << 16) | (std::uint64_t{static_cast<std::uint8_t>(f.kind)} << 9) |
             (std::uint64_t{f.extended} << 8) | f.len);
  std::uint64_t data = 0;
  std::memcpy(&data, f.data.data(), std::min<std::size_t>(f.len, sizeof data));
  mix(h, data);
  if (!stats_.empty()) stats_[robot].add(frame);
  if (!checkers_.empty()) checkers_[robot].add(frame);
  if (!recorded_.empty()) recorded_[robot].push_back(frame);
}

std::uint64_t BusWatch::trace_hash() const noexcept {
  std::uint64_t h = kHashStart;
  for (const std::uint64_t bus : hashes_) mix(h, bus);
  return h;
}

std::uint64_t BusWatch::ftt_violations(std::size_t robot) const {
  return robot < checkers_.size() ? checkers_[robot].violation_count() : 0;
}

void BusWatch::fill(std::vector<BusDetail>& buses, Nanos now) {
  if (stats_.empty()) {
    for (std::size_t r = 0; r < interfaces_.size(); ++r) stats_.emplace_back(session_.messages, session_.ftt.bit_rate);
  }
  buses.resize(stats_.size());
  for (std::size_t r = 0; r < stats_.size(); ++r) {
    timing::LiveBusStats& stats = stats_[r];
    stats.advance(now);
    BusDetail& b = buses[r];
    b.frames = counts_[r];
    b.load = stats.load();
    b.jitter_ms = stats.jitter_ms();
  }
}

// By time, then robot, then the order each bus received them.
std::string BusWatch::trace() const {
  struct Line {
    Nanos time;
    std::size_t bus;
    std::size_t order;
  };
  std::vector<Line> lines;
  for (std::size_t r = 0; r < recorded_.size(); ++r) {
    for (std::size_t i = 0; i < recorded_[r].size(); ++i) lines.push_back({recorded_[r][i].time, r, i});
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.time != b.time ? a.time < b.time : a.bus < b.bus; });
  std::string out;
  for (const Line& l : lines) {
    out += frames::format_log_line(l.time, interfaces_.at(l.bus), recorded_[l.bus][l.order].frame);
    out += '\n';
  }
  return out;
}

}  // namespace canhil::emulator
