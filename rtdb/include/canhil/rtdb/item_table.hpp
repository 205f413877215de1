// canhil/rtdb/item_table.hpp — a team's RTDB items: id <-> name, size, which
// agent has which (shared or local), agent names.
//
// Read from the team's generated files (rtdb_user.h and rtdb.ini, CAMBADA's
// formats) or taken from the RTDB linked into this process. Immutable and
// cheap to copy; thread-compatible.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

struct canhil_rtdb_table;  // canhil/rtdb/rtdb_table.h

namespace canhil::rtdb {

/// How an agent's schema has an item.
enum class ItemKind { kNone, kShared, kLocal };

class ItemTable {
 public:
  /// The team's generated header (`#define NAME ID` for agents and items,
  /// N_AGENTS, N_ITEMS) and its rtdb.ini ("# N AGENT" sections of
  /// "ID SIZE PERIOD s|l" lines). SetupError ("FILE:LINE: what; what to do")
  /// when either does not parse or they disagree: an ini item or agent the
  /// header does not name, or numbers otherwise. A header item that no agent
  /// has in the ini is kept (CAMBADA's own pair has one, REMOTE_CMD): it is
  /// listed by unconfigured(), and require() refuses it by name.
  static ItemTable from_files(const std::filesystem::path& rtdb_user_h, const std::filesystem::path& rtdb_ini);
  /// An rtdb.ini alone: items are named "item<ID>".
  static ItemTable from_ini(const std::filesystem::path& rtdb_ini);
  /// The table of the RTDB linked into this process (canhil::rtdb: canhil's
  /// configuration, or the rtdb.ini DB_set_config_file named). SetupError when
  /// that library cannot read its table.
  static ItemTable builtin();

  /// The id of the item called `item` (for a table from an ini alone,
  /// "item<ID>"), or nullopt.
  std::optional<int> id(std::string_view item) const;
  /// The item's size in bytes, or nullopt when no agent has it (or no such id).
  std::optional<std::size_t> size(int id) const;
  /// The item's name ("item<ID>" when the table has none); "" out of range.
  std::string name(int id) const;
  /// Item ids are 0 .. item_count() - 1 (not all need to exist: see size()).
  int item_count() const noexcept { return static_cast<int>(items_.size()); }

  int agent_count() const noexcept { return static_cast<int>(agents_.size()); }
  /// The agent's name ("" out of range).
  std::string agent_name(int agent) const;
  /// The number of the agent called `name`, or nullopt.
  std::optional<int> agent(std::string_view name) const;

  /// How agent `agent`'s schema has item `id` (kNone out of range).
  ItemKind kind(int agent, int id) const noexcept;
  /// The ids agent `agent` has as `kind` (kShared or kLocal), ascending.
  std::vector<int> items_of(int agent, ItemKind kind) const;
  /// Ids the header names but no agent has.
  const std::vector<int>& unconfigured() const noexcept { return unconfigured_; }

  /// Where the table came from, for messages: the files, or the library.
  const std::string& source() const noexcept { return source_; }

 private:
  struct Item {
    std::string name;
    std::size_t size = 0;  // 0: no agent has it
  };
  ItemTable() = default;
  static ItemTable from_c(const canhil_rtdb_table& table, std::string source, bool header_names);

  std::vector<Item> items_;
  std::vector<std::string> agents_;
  std::vector<std::vector<ItemKind>> kinds_;  // [agent][id]
  std::vector<int> unconfigured_;
  std::string source_;
};

}  // namespace canhil::rtdb
