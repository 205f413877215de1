#include "canhil/rtdb/item_table.hpp"

#include <algorithm>
#include <array>
#include <memory>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/rtdb.h"
#include "canhil/rtdb/rtdb_table.h"

namespace canhil::rtdb {
namespace {

std::string fallback_name(int id) { return "item" + std::to_string(id); }

ItemKind kind_of(int membership) {
  return membership == 1 ? ItemKind::kShared : membership == 0 ? ItemKind::kLocal : ItemKind::kNone;
}

ItemTable load(const std::filesystem::path* rtdb_user_h, const std::filesystem::path& rtdb_ini,
               ItemTable (*make)(const canhil_rtdb_table&, std::string, bool)) {
  std::array<char, 1024> error{};
  const std::string ini = rtdb_ini.string();
  const std::string header = rtdb_user_h != nullptr ? rtdb_user_h->string() : std::string();
  const std::unique_ptr<canhil_rtdb_table, void (*)(canhil_rtdb_table*)> table(
      canhil_rtdb_table_load(ini.c_str(), rtdb_user_h != nullptr ? header.c_str() : nullptr, error.data(),
                             error.size()),
      &canhil_rtdb_table_free);
  if (!table) throw SetupError(error.data());
  return make(*table, rtdb_user_h != nullptr ? header + " + " + ini : ini, rtdb_user_h != nullptr);
}

}  // namespace

ItemTable ItemTable::from_c(const canhil_rtdb_table& t, std::string source, bool header_names) {
  ItemTable out;
  out.source_ = std::move(source);
  out.items_.reserve(t.n_items);
  out.agents_.reserve(t.n_agents);
  out.kinds_.reserve(t.n_agents);
  for (std::uint32_t i = 0; i < t.n_items; ++i) {
    out.items_.push_back(Item{t.items[i].name, t.items[i].size});
    const int id = static_cast<int>(i);
    if (header_names && t.items[i].size == 0 && t.items[i].name != fallback_name(id)) out.unconfigured_.push_back(id);
  }
  for (std::uint32_t a = 0; a < t.n_agents; ++a) {
    out.agents_.emplace_back(t.agents[a].name);
    std::vector<ItemKind> kinds(t.n_items);
    for (std::uint32_t i = 0; i < t.n_items; ++i) kinds[i] = kind_of(t.agents[a].membership[i]);
    out.kinds_.push_back(std::move(kinds));
  }
  return out;
}

ItemTable ItemTable::from_files(const std::filesystem::path& rtdb_user_h, const std::filesystem::path& rtdb_ini) {
  return load(&rtdb_user_h, rtdb_ini, &ItemTable::from_c);
}

ItemTable ItemTable::from_ini(const std::filesystem::path& rtdb_ini) {
  return load(nullptr, rtdb_ini, &ItemTable::from_c);
}

ItemTable ItemTable::builtin() {
  const int agents = DB_agent_count();
  const char* source = DB_config_source();
  if (agents <= 0) {
    throw SetupError(std::string("canhil's RTDB cannot read its item table") +
                     (source ? " " + std::string(source) : "") +
                     " (the reason is above); fix it, or name another with DB_set_config_file");
  }
  ItemTable out;
  out.source_ = std::string("canhil's linked RTDB (") + (source != nullptr ? source : "?") + ")";
  const int n = DB_item_count();
  out.items_.reserve(static_cast<std::size_t>(n));
  out.agents_.reserve(static_cast<std::size_t>(agents));
  out.kinds_.reserve(static_cast<std::size_t>(agents));
  for (int id = 0; id < n; ++id) {
    const char* name = DB_item_name(id);
    const int size = DB_item_size(id);
    out.items_.push_back(
        Item{name != nullptr ? name : fallback_name(id), size > 0 ? static_cast<std::size_t>(size) : 0});
  }
  for (int a = 0; a < agents; ++a) {
    const char* name = DB_agent_name(a);
    out.agents_.emplace_back(name != nullptr ? name : "agent" + std::to_string(a));
    std::vector<ItemKind> kinds(static_cast<std::size_t>(n));
    for (int id = 0; id < n; ++id) kinds[static_cast<std::size_t>(id)] = kind_of(DB_item_shared(a, id));
    out.kinds_.push_back(std::move(kinds));
  }
  return out;
}

std::optional<int> ItemTable::id(std::string_view item) const {
  const auto at = std::find_if(items_.begin(), items_.end(), [&](const Item& i) { return i.name == item; });
  if (at == items_.end()) return std::nullopt;
  return static_cast<int>(at - items_.begin());
}

std::optional<std::size_t> ItemTable::size(int id) const {
  if (id < 0 || id >= item_count() || items_[static_cast<std::size_t>(id)].size == 0) return std::nullopt;
  return items_[static_cast<std::size_t>(id)].size;
}

std::string ItemTable::name(int id) const {
  return id >= 0 && id < item_count() ? items_[static_cast<std::size_t>(id)].name : std::string();
}

std::string ItemTable::agent_name(int agent) const {
  return agent >= 0 && agent < agent_count() ? agents_[static_cast<std::size_t>(agent)] : std::string();
}

std::optional<int> ItemTable::agent(std::string_view name) const {
  const auto at = std::find(agents_.begin(), agents_.end(), name);
  if (at == agents_.end()) return std::nullopt;
  return static_cast<int>(at - agents_.begin());
}

ItemKind ItemTable::kind(int agent, int id) const noexcept {
  if (agent < 0 || agent >= agent_count() || id < 0 || id >= item_count()) return ItemKind::kNone;
  return kinds_[static_cast<std::size_t>(agent)][static_cast<std::size_t>(id)];
}

std::vector<int> ItemTable::items_of(int agent, ItemKind kind) const {
  std::vector<int> out;
  for (int id = 0; id < item_count(); ++id) {
    if (kind != ItemKind::kNone && this->kind(agent, id) == kind) out.push_back(id);
  }
  return out;
}

}  // namespace canhil::rtdb
