// canhil/emulator/laptop_link.hpp — the seam between a run and the team's
// laptop software: everything canhil writes into or reads from the team's RTDB
// and how it wakes the team's agents.
//
//   RTDB    canhil's linked RTDB, or the team's own library loaded at run
//           time (rtdb::open_library: its simulator API, its rtdb.ini, its
//           rtdb_user.h ids), every agent's database reached (DB_init_all).
//   layout  what each item holds, in the team's structs and units
//           (rtdb::Layout: "canhil", "cambada" or the team's description).
//   PMan    each robot's omni-vision master (pman::Masters: canhil's PMan or
//           the team's libpman), its table created before anything else runs,
//           ticked after every VISION_INFO.
//   coach   the base station's COACH_INFO / FORMATION_INFO, written at every
//           change of the coach's orders and again every coach period.
//   comm    the replicator: each agent's shared items copied into the others'
//           databases every period, as the team's wireless would.
//
// Every item it writes or reads is checked at construction against the team's
// table (its size, which agents have it): a mismatch stops the run at start
// with a SetupError naming the item, never a write of the wrong size.
//
// Thread-compatible: used from the thread that steps the world.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "canhil/base/time.hpp"
#include "canhil/emulator/coach.hpp"
#include "canhil/emulator/scenario.hpp"
#include "canhil/kinematics/omni.hpp"
#include "canhil/pman/masters.hpp"
#include "canhil/rtdb/database.hpp"
#include "canhil/rtdb/layout.hpp"
#include "canhil/rtdb/replicator.hpp"
#include "canhil/vision_emu/vision.hpp"

namespace canhil::emulator {

/// The defaults of a LaptopSide filled in: canhil's RTDB in canhil's layout
/// (cambada's for a team library), canhil's PMan where `realtime` (nothing
/// outside the process follows virtual time: no PMan there unless asked),
/// the replicator when the run has more than one robot. SetupError for a team
/// library without its rtdb.ini, or an rtdb_user.h without a team library.
LaptopSide resolve_laptop(LaptopSide side, std::size_t robots, bool realtime);

/// The layout a resolved side names: a shipped one by name, else the file.
/// SetupError (rtdb::LayoutError) for a file that cannot be read or parsed.
rtdb::Layout load_layout(const std::string& name);

/// Whether `layout` tells a team's agents which goal their team attacks
/// (COACH_INFO's `attacks` quantity, e.g. CAMBADA's goalColor).
bool layout_tells_attacks(const rtdb::Layout& layout);

class LaptopLink {
 public:
  /// `side` as resolve_laptop() gives it; `agents` the team's robots' agent
  /// numbers, `coach` the team's orders (its robots' players); `rtdb_set` the
  /// team's set of databases (0, or 1 for the second team: rtdb::open_builtin).
  LaptopLink(const LaptopSide& side, const std::vector<int>& agents, const CoachState& coach, int rtdb_set = 0);
  ~LaptopLink();
  LaptopLink(const LaptopLink&) = delete;
  LaptopLink& operator=(const LaptopLink&) = delete;

  /// Robot r's frame into its agent's VISION_INFO, then its agent woken: one
  /// tick of its PMan table and, with signal_frames(), canhil's RTDB's frame
  /// signal (or, with deferred activation, both kept for activate()).
  void vision_frame(std::size_t robot, const vision_emu::VisionFrame& frame);
  /// After each frame, post canhil's RTDB's frame signal too (agents that wait
  /// on DB_wait_frame: the real-time and external drivers; a team's library
  /// has no such signal). Off by default: the in-process reference agent is
  /// told directly.
  void signal_frames(bool on) noexcept { signal_frames_ = on; }
  /// Keep each frame's PMan tick until activate() instead of sending it at
  /// once. In lockstep the agents' clocks must read the frame's instant when
  /// they wake: the driver moves the processes' clock there first, then
  /// activates (an agent woken before that reads the previous instant's time
  /// for part of its cycle, whenever the scheduler lets it run first).
  void defer_activation(bool deferred) noexcept { deferred_ = deferred; }
  /// The wake-ups kept since the last call (PMan ticks, frame signals), in
  /// the order of their frames; returns how many frames they were for.
  std::size_t activate();
  /// The coach's orders into every robot's database (COACH_INFO as the base
  /// station's copy and the robot's own, where the team's table has them).
  void write_coach(const CoachState& coach);
  /// Periodic work at `now`: the coach again every coach period, the replicator
  /// every replication period (its delayed copies at any step).
  void step(Nanos now, const CoachState& coach);
  /// Every item of robot r's agent zeroed in its own database (a fresh start
  /// for the in-process reference laptop).
  void clear_items(std::size_t robot);
  /// Asks robot r's handler to set its odometry to `at` (CMD_SETPOSE in the
  /// team's layout: x, y, heading, command 0, pending). SetupError when the
  /// layout or the team's table lacks it.
  void place(std::size_t robot, const kinematics::Pose& at);
  /// The RTDB's clock (rtdb::Database::set_clock); false where the library keeps the wall clock.
  bool set_clock(std::int64_t (*now)(void* context), void* context) { return db_->set_clock(now, context); }
  /// Robot r's pose as its handler reported it (CMD_POS), when the layout carries it.
  std::optional<kinematics::Pose> reported_pose(std::size_t robot);

  rtdb::Database& database() noexcept { return *db_; }
  const rtdb::Layout& layout() const noexcept { return layout_; }
  /// The PMan masters, or nullptr (pman = "none").
  pman::Masters* masters() noexcept { return masters_.get(); }
  const rtdb::ReplicatorStats* replicator_stats() const noexcept;
  std::uint64_t vision_writes() const noexcept { return vision_writes_; }
  std::uint64_t coach_writes() const noexcept { return coach_writes_; }
  /// Lines for the end of a run: the RTDB, the layout, PMan's counts per process, the replicator.
  std::string summary() const;

 private:
  struct Robot;
  struct CoachItem {
    int id = -1;
    std::unique_ptr<rtdb::ItemBuffer> buffer;
    std::vector<std::pair<int, int>> targets;  // (space, owner) of every copy written
    // COACH_INFO's (FORMATION_INFO: zeros)
    rtdb::Quantity game_state, running, role_auto, role, attacks, relocations;
  };
  std::unique_ptr<rtdb::Database> db_;
  rtdb::Layout layout_;
  std::unique_ptr<pman::Masters> masters_;
  std::unique_ptr<rtdb::Replicator> replicator_;
  std::vector<std::unique_ptr<Robot>> robots_;
  std::vector<CoachItem> coach_items_;
  std::set<std::string> warned_;               // names the layout cannot store, warned of once
  std::vector<std::array<double, 2>> points_;  // scratch for a frame's points
  std::vector<rtdb::ByteRange> changed_;       // scratch: the parts of VISION_INFO a frame wrote
  Nanos coach_period_;
  Nanos next_coach_{0};
  Nanos next_replicate_{0};
  bool deferred_ = false;
  bool signal_frames_ = false;
  std::vector<int> pending_;  // agents whose wake-up is kept (deferred activation)
  void wake(int agent);
  std::uint64_t vision_writes_ = 0;
  std::uint64_t coach_writes_ = 0;
};

}  // namespace canhil::emulator
