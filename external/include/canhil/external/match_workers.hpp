// canhil/external/match_workers.hpp — matches in worker processes, one per
// core (`canhil match --jobs N`): each worker is forked from canhil with
// everything loaded, plays the seeds it is handed one at a time and sends back
// each match's record (one line of text: the command's JSON); the records come out in the order of the seeds, whatever
// the order they finish in, so that a batch gives the same records and the same table with any number of workers. A
// worker that dies in a match gives that match a failed record, and another takes its place: the batch goes on.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace canhil::external {

struct MatchJobs {
  /// Plays one match in a worker: its number in the batch (1-based) and seed;
  /// `progress` with the virtual seconds played so far. Returns its record:
  /// one line (no newline in it).
  std::function<std::string(int number, std::uint64_t seed, const std::function<void(double)>& progress)> play;
  /// The record of a match whose worker died (`why`: how).
  std::function<std::string(std::uint64_t seed, const std::string& why)> failed;
  /// Each record, in the order of the seeds.
  std::function<void(const std::string& record)> done;
  /// Progress as the workers report it: a match's seed and its virtual seconds so far.
  std::function<void(std::uint64_t seed, double played_s)> progress;
  /// When set: called in each worker, with its index, after it chose its
  /// RTDB keys (in the batch's IPC namespace) and before its first match.
  /// What it returns the worker holds until it ends (`canhil match
  /// --external`: an IPC namespace and a bus of its own). SetupError: the
  /// worker's error, as play()'s.
  std::function<std::shared_ptr<void>(int index)> enter;
};

/// Plays `seeds` in `workers` processes; stops handing out seeds once `stop`
/// is set (the matches under way finish as play() decides). Throws SetupError
/// with a worker's message when play() or enter() threw SetupError (the
/// scenario itself is wrong, or the machine: every match would fail), after
/// done() has had the records the other workers finished.
void play_in_workers(const std::vector<std::uint64_t>& seeds, int workers, const MatchJobs& jobs,
                     const std::atomic<bool>& stop);

}  // namespace canhil::external
