// canhil/pman/masters.hpp — the omni-vision's side of PMan for every robot
// of a run, in one process: each robot's table (keys 0x9011 + 2 x agent),
// its processes registered before any client can attach, one tick per vision
// frame, and what happened to each process (activations, epilogues, deadline
// misses).
//
// Two implementations, one interface: canhil's own PMan (builtin_masters(),
// table-compatible with CAMBADA's, docs/pman.md) or a team's libpman loaded at
// run time (library_masters(): CAMBADA's API, PMAN_init2 / PMAN_procadd /
// PMAN_tick / PMAN_query / PMAN_close, its process globals switched per robot
// as its own pman_save_ids / pman_switch_id would).
//
// Epilogues and deadline misses are canhil's counts, the same for both: at
// each tick, a process activated at the previous one has either ended its
// cycle (PMAN_epilogue: status IDLE, last_finish after last_start: an
// epilogue) or not (a deadline miss: its deadline is the next activation).
//
// Thread-compatible: one thread uses a Masters object at a time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace canhil::pman {

/// One registered process of a robot's table, as the table has it.
struct Process {
  std::string name;
  int pid = 0;                      ///< 0 until its client attached
  int status = 0;                   ///< PROC_S_* (pman.h): 3 idle, 2 activated and running
  std::uint64_t activations = 0;    ///< the table's count (PROC_nact)
  std::int64_t last_start_us = 0;   ///< gettimeofday of its last activation, or 0
  std::int64_t last_finish_us = 0;  ///< of its last epilogue, or 0
  bool idle() const noexcept;       ///< waiting for its next activation (its cycle ended)
};

/// What canhil counted for one process over the run.
struct ProcessCounts {
  std::string name;
  std::uint64_t activations = 0;      ///< ticks that activated it (it was attached)
  std::uint64_t epilogues = 0;        ///< activations whose cycle ended by the next tick
  std::uint64_t deadline_misses = 0;  ///< activations whose cycle had not ended by the next tick
  std::uint64_t gone = 0;             ///< times its client left the table at a tick (it died, or detached)
};

class Masters {
 public:
  virtual ~Masters() = default;
  Masters(const Masters&) = delete;
  Masters& operator=(const Masters&) = delete;

  /// Creates robot `agent`'s table (taking over one left by a crashed run),
  /// registers `processes` (period 1, phase 0), then publishes it so clients
  /// can attach. SetupError saying what to do (no permission for the keys,
  /// another master's table in use, a name too long).
  virtual void open(int agent, const std::vector<std::string>& processes) = 0;
  /// One tick of robot `agent`'s table (after its VISION_INFO is written):
  /// every process due is activated (SIGCONT). Returns how many were signalled.
  virtual int tick(int agent) = 0;
  /// The registered processes of robot `agent`'s table, now.
  virtual std::vector<Process> query(int agent) = 0;
  /// Whether every attached process of robot `agent` has ended its cycle
  /// (what a lockstep driver waits for before moving past a frame).
  bool all_idle(int agent);
  /// canhil's counts per process of robot `agent`.
  virtual std::vector<ProcessCounts> counts(int agent) const = 0;
  /// Ends every table as the stock master does (PMAN_CLFREE: SIGINT to the
  /// attached clients, table and semaphore removed). Also done by the destructor.
  virtual void close_all() = 0;
  /// "canhil's own PMan" or the library's path.
  virtual std::string description() const = 0;

 protected:
  Masters() = default;
};

/// canhil's own PMan (the canhil::pman library's handle API), its tables at
/// the first team's keys (set 0: 0x9011 + 2 x agent) or the second team's
/// (set 1: 0x100 higher, where canhil's PMAN_init looks with SECOND_RTDB=1).
std::unique_ptr<Masters> builtin_masters(int set = 0);

/// A team's PMan library (a shared object with CAMBADA's API), loaded with
/// dlopen. SetupError: no such file, not loadable, a symbol missing (named).
std::unique_ptr<Masters> library_masters(const std::filesystem::path& shared_object);

/// The processes of every table at keys 0x9011 + 2 x agent and the second
/// team's 0x9111 + 2 x agent, agent 1..6, read without attaching (for
/// `canhil pman list`; any master's, canhil's or a team's, as long as the
/// table is CAMBADA's layout). Agents without a table are left out.
struct TableView {
  int agent = 0;
  int set = 0;  ///< 0 the first team's keys, 1 the second's
  int key = 0;
  std::uint64_t ticks = 0;
  std::vector<Process> processes;
};
std::vector<TableView> read_tables(int first_agent = 1, int last_agent = 6);

}  // namespace canhil::pman
