// canhil/rtdb/database.hpp — one narrow way to a team's RTDB, whichever
// library holds it: canhil's linked RTDB (open_builtin) or the team's own
// shared library with CAMBADA's C API, loaded at run time (open_library).
//
// A Database reaches the databases ("memory spaces") of every agent
// (Scope::kAllAgents: DB_init_all, as a simulator) or of this process's agent
// (Scope::kOneAgent: DB_init with AGENT, as an agent). Item `id` of agent
// `owner` in agent `space`'s database is the owner's own item when
// owner == space, else that database's copy of the owner's shared item.
//
// Non-copyable; thread-compatible (one thread at a time, or the caller's
// lock). One per library and process: the C libraries keep their state in
// globals. Closing (destruction) frees (DB_free_all / DB_free) and unloads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/rtdb/byte_range.hpp"
#include "canhil/rtdb/item_table.hpp"

namespace canhil::rtdb {

enum class Scope {
  kAllAgents,  ///< every agent's database (DB_init_all)
  kOneAgent,   ///< this process's agent's database (DB_init, AGENT)
};

class Database {
 public:
  /// get()'s age for an item never written: infinitely old (CAMBADA's library
  /// answers INT_MIN there; canhil's ages such an item from the database's
  /// creation instead).
  static constexpr int kNeverWritten = std::numeric_limits<int>::max();

  virtual ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  /// The team's items, as the library was opened with (checked against it).
  const ItemTable& items() const noexcept { return items_; }
  Scope scope() const noexcept { return scope_; }
  /// The agents whose databases this process reaches, ascending.
  const std::vector<int>& spaces() const noexcept { return spaces_; }
  bool serves(int space) const noexcept;
  /// What holds the RTDB, for messages: "canhil's linked RTDB (...)" or the library's path.
  const std::string& library() const noexcept { return library_; }

  /// Item `id` of agent `owner` written into agent `space`'s database
  /// (owner == space: its own item; else the copy of owner's shared item),
  /// aged `life_ms` (>= 0). The space must be served, the item in it, and
  /// `bytes` exactly the item's size: a broken invariant otherwise (callers
  /// check with require() at set-up).
  virtual void put(int space, int owner, int id, std::span<const std::byte> bytes, int life_ms = 0) = 0;
  /// put() of an item image that differs from the one last put into this
  /// slot only inside `changed` (offsets into `bytes`), by the only writer of
  /// the slot: canhil's library copies just those, in one write (DB_put_ranges);
  /// a library without it is given the whole item. Same preconditions as put().
  virtual void put_ranges(int space, int owner, int id, std::span<const std::byte> bytes,
                          std::span<const ByteRange> changed, int life_ms = 0) {
    (void)changed;
    put(space, owner, id, bytes, life_ms);
  }
  /// Whether put_ranges() writes only the ranges (else they need not be worked out).
  virtual bool puts_ranges() const noexcept { return false; }
  /// Tells agent `agent`'s process that a camera frame is in its database:
  /// canhil's RTDB posts its frame signal (DB_signal_frame on the agent's
  /// memory space in this database's set; DB_wait_frame returns). A team's
  /// library has no such signal (its agents are woken through PMan): nothing.
  virtual void signal_frame(int agent) { (void)agent; }
  /// Items stamped and aged by `now` (nanoseconds; nullptr: the wall clock
  /// again) instead of the wall clock: canhil's RTDB only, whose clock is
  /// one per process, for every set (false: the library keeps the wall
  /// clock, as a team's does).
  virtual bool set_clock(std::int64_t (*now)(void* context), void* context) {
    (void)now;
    (void)context;
    return false;
  }
  /// Reads it into `bytes` (same preconditions). The age in ms,
  /// kNeverWritten for an item never written, or nullopt when the library
  /// says the item does not exist.
  virtual std::optional<int> get(int space, int owner, int id, std::span<std::byte> bytes) = 0;

  /// The item's id after checking that agent `space` has it (shared or local)
  /// with exactly `size` bytes. SetupError otherwise, naming the item, the
  /// table's size and the size asked, and what to do; also for a space this
  /// Database does not serve.
  int require(std::string_view item, std::size_t size, int space) const;
  /// The same for agent `owner`'s item as agent `space`'s database holds it:
  /// its own (owner == space) or a copy of owner's shared item.
  int require(std::string_view item, std::size_t size, int space, int owner) const;

 protected:
  Database(ItemTable items, Scope scope, std::vector<int> spaces, std::string library);
  /// The invariants put() and get() share (aborts with a message).
  void demand_slot(int space, int owner, int id, std::size_t size) const {
    if (size == 0 || slot_size(space, owner, id) != size) broken_slot(space, owner, id, size);
  }

 private:
  // The size of item `id` of `owner` in `space`'s database, 0 when the slot
  // is not there (a space not served, an item neither its own nor shared):
  // one load, where the table's own answers take several (put and get ask
  // it a few thousand times a simulated second).
  std::size_t slot_size(int space, int owner, int id) const noexcept {
    const auto agents = static_cast<unsigned>(items_.agent_count());
    const auto ids = static_cast<unsigned>(items_.item_count());
    if (static_cast<unsigned>(space) >= agents || static_cast<unsigned>(owner) >= agents ||
        static_cast<unsigned>(id) >= ids) {
      return 0;
    }
    return slot_sizes_[(static_cast<std::size_t>(space) * agents + static_cast<unsigned>(owner)) * ids +
                       static_cast<unsigned>(id)];
  }
  /// demand_slot's verdict when the slot is not what was asked: says which invariant broke, and aborts.
  [[noreturn]] void broken_slot(int space, int owner, int id, std::size_t size) const;

  ItemTable items_;
  Scope scope_;
  std::vector<int> spaces_;
  std::string library_;
  std::vector<std::size_t> slot_sizes_;  // [space][owner][id], as slot_size()
};

/// canhil's linked RTDB (canhil::rtdb): every agent (DB_init_all) or this
/// process's agent (DB_init, AGENT). Its table is ItemTable::builtin().
/// SetupError when it cannot attach (the library's reason is on stderr).
/// Several may be open at once (canhil's inits nest). `set` 1 is the second
/// team's set of databases (DB_init_all(1): keys 64 higher), 0 the first;
/// kOneAgent takes its set from SECOND_RTDB instead. Either way the spaces
/// put() and get() take are the team's agent numbers.
std::unique_ptr<Database> open_builtin(Scope scope, int set = 0);

/// A team's RTDB library (its librtdb.so, or canhil's), loaded with
/// dlopen(RTLD_NOW | RTLD_LOCAL): DB_set_config_file(config_file) when given,
/// then DB_init_all / DB_put_in / DB_get_from / DB_free_all (kAllAgents) or
/// DB_init / DB_put / DB_get / DB_free (kOneAgent; DB_put_in and Whoami when
/// present). `table` must describe the rtdb.ini the library reads: at open,
/// every item the table gives a space is read once through the library (and,
/// where the library is canhil's, its sizes compared). SetupError saying what
/// to do: no such library, a missing symbol (named), the library already open
/// in this process for that set, init failed, a table the library
/// contradicts. `set` as for open_builtin: the second team's set is
/// DB_init_all(1) and memory spaces N + agent (CAMBADA's numbering when its
/// table has MAX_AGENTS agents); both sets of one library read one rtdb.ini.
std::unique_ptr<Database> open_library(const std::filesystem::path& so, ItemTable table, Scope scope,
                                       std::optional<std::filesystem::path> config_file, int set = 0);

}  // namespace canhil::rtdb
