// canhil/emulator/bus_watch.hpp — every robot's bus as a driver that sees its
// frames watches it, one rule for every driver: frames counted, optionally
// kept for a candump trace (in time order, then robot, then arrival),
// optionally checked against `canhil timing`'s rules as they come (constant
// memory), and, once someone watches the run in detail (the viewer's plots),
// measured: load and jitter over the last whole second. Until then the
// measuring costs nothing. One thread adds frames and reads the results.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "canhil/emulator/session.hpp"
#include "canhil/timing/analysis.hpp"
#include "canhil/timing/live.hpp"

namespace canhil::emulator {

/// A checker of one robot's bus by `canhil timing`'s rules with the session's
/// elementary cycle and bit rate, counting violations only (constant memory).
timing::TimingAnalyzer ftt_checker(const SessionOptions& options);

class BusWatch {
 public:
  struct Options {
    bool record_trace = true;   ///< keep the frames for trace()
    bool check_timing = false;  ///< ftt_violations()
  };
  /// One bus per robot of `session` (which must outlive the watch).
  BusWatch(const Session& session, Options options);

  /// A frame on robot r's bus at its time (frames come in time order per bus).
  void add(std::size_t robot, const frames::TimedFrame& frame);

  std::uint64_t frames(std::size_t robot) const { return counts_.at(robot); }
  /// A hash of every frame on every bus (time, identifier, kind, length,
  /// data: three 64-bit words a frame, each mixed in by a multiply), bus by bus
  /// in robot order: two runs carried the same frames at the same times when
  /// it is equal. Always kept (a few cycles a frame), so a match can be checked
  /// anywhere without its trace.
  std::uint64_t trace_hash() const noexcept;
  /// Violations on robot r's bus so far (check_timing; else 0).
  std::uint64_t ftt_violations(std::size_t robot) const;
  /// Every bus as one candump log (record_trace; else empty).
  std::string trace() const;
  /// Fills `buses` (one per robot) with the counts and, measured up to `now`,
  /// load and jitter; the measuring starts at the first call.
  void fill(std::vector<BusDetail>& buses, Nanos now);

 private:
  const SessionOptions& session_;
  std::vector<std::string> interfaces_;
  Options options_;
  std::vector<std::uint64_t> counts_;
  std::vector<std::uint64_t> hashes_;  // per bus, FNV-1a
  std::vector<std::vector<frames::TimedFrame>> recorded_;
  std::vector<timing::TimingAnalyzer> checkers_;
  std::vector<timing::LiveBusStats> stats_;  // once fill() was called
};

}  // namespace canhil::emulator
