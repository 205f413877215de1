#include "canhil/rtdb/database.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <utility>

#include "canhil/base/demand.hpp"
#include "canhil/base/second_set.h"
#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/rtdb.h"

namespace canhil::rtdb {
namespace {

// CAMBADA's C API, from whichever library holds it.
struct CApi {
  int (*init_all)(int) = nullptr;
  void (*free_all)(int) = nullptr;
  int (*put_in)(int, int, int, void*, int) = nullptr;
  int (*get_from)(int, int, int, void*) = nullptr;
  int (*init_one)() = nullptr;
  void (*free_one)() = nullptr;
  int (*put_one)(int, void*) = nullptr;
  int (*get_one)(int, int, void*) = nullptr;
  int (*whoami)() = nullptr;
  void (*set_config_file)(const char*) = nullptr;
  int (*item_size)(int) = nullptr;  // canhil's extension, where the library has it
  int (*put_ranges)(int, int, int, const void*, const std::size_t*, int, int) = nullptr;  // canhil's too
  int (*signal_frame)(int) = nullptr;                                                     // canhil's linked RTDB only
  void (*set_clock)(std::int64_t (*)(void*), void*) = nullptr;                            // canhil's linked RTDB only
};

// The libraries open in this process, with the set (team) each serves: a
// second Database on one set would share (and free) the first one's globals;
// the two sets of one library are apart (DB_init_all(0) and (1)).
std::set<std::pair<void*, int>>& open_libraries() {
  static std::set<std::pair<void*, int>> open;
  return open;
}
// The configuration file each open library was given (both sets read one).
std::map<void*, std::string>& library_configs() {
  static std::map<void*, std::string> configs;
  return configs;
}
std::mutex& open_libraries_mutex() {
  static std::mutex m;
  return m;
}

// A library loaded and registered as open; unloaded with it.
class LoadedLibrary {
 public:
  LoadedLibrary(const std::filesystem::path& so, int set, const std::string& config) : path_(so.string()), set_(set) {
    handle_ = dlopen(path_.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) {
      const char* why = dlerror();
      throw SetupError("cannot load the RTDB library " + path_ + ": " + (why != nullptr ? why : "?") +
                       "; give the path of the team's RTDB shared library (its librtdb.so)");
    }
    const std::lock_guard<std::mutex> lock(open_libraries_mutex());
    if (!open_libraries().insert({handle_, set_}).second) {
      dlclose(handle_);
      throw SetupError("the RTDB library " + path_ + " is already open in this process for " +
                       (set_ == 0 ? "the first" : "the second") +
                       " team; open it once per team (its state is global) and share that Database");
    }
    const bool other_set_open = open_libraries().count({handle_, 1 - set_}) != 0;
    if (other_set_open && library_configs()[handle_] != config) {
      open_libraries().erase({handle_, set_});
      dlclose(handle_);
      throw SetupError("the RTDB library " + path_ + " already serves the other team with " +
                       library_configs()[handle_] + ", and one library reads one item table: give both teams the " +
                       "same rtdb.ini, or this team a copy of the library under another path");
    }
    shares_table_ = other_set_open;
    library_configs()[handle_] = config;
  }
  ~LoadedLibrary() {
    {
      const std::lock_guard<std::mutex> lock(open_libraries_mutex());
      open_libraries().erase({handle_, set_});
      if (open_libraries().count({handle_, 1 - set_}) == 0) library_configs().erase(handle_);
    }
    dlclose(handle_);
  }
  LoadedLibrary(const LoadedLibrary&) = delete;
  LoadedLibrary& operator=(const LoadedLibrary&) = delete;

  /// The other team's set was open already, with this configuration file.
  bool shares_table() const noexcept { return shares_table_; }

  /// The function `name`, or nullptr (and `name` added to `missing` when given).
  template <class F>
  F symbol(const char* name, std::vector<std::string>* missing) const {
    void* p = dlsym(handle_, name);
    if (p == nullptr && missing != nullptr) missing->emplace_back(name);
    return reinterpret_cast<F>(p);  // POSIX: dlsym's result is the function's address
  }

 private:
  std::string path_;
  int set_ = 0;
  bool shares_table_ = false;
  void* handle_ = nullptr;
};

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) out += (out.empty() ? "" : ", ") + w;
  return out;
}

// Both backends: canhil's linked library and a loaded one, through CApi.
class CApiDatabase final : public Database {
 public:
  // `set`: the team's set of databases (0 or 1); its memory spaces are
  // set * agents + agent in the library's calls.
  CApiDatabase(ItemTable items, Scope scope, std::vector<int> spaces, std::string library, const CApi& api,
               std::unique_ptr<LoadedLibrary> loaded, int set)
      : Database(std::move(items), scope, std::move(spaces), std::move(library)),
        api_(api),
        loaded_(std::move(loaded)),
        set_(set),
        first_space_(set * this->items().agent_count()) {}
  void signal_frame(int agent) override {
    if (api_.signal_frame != nullptr) api_.signal_frame(first_space_ + agent);
  }
  bool set_clock(std::int64_t (*now)(void* context), void* context) override {
    if (api_.set_clock == nullptr) return false;
    api_.set_clock(now, context);
    return true;
  }
  ~CApiDatabase() override {  // frees, then (loaded_) unloads
    if (scope() == Scope::kAllAgents) {
      api_.free_all(set_);
    } else {
      api_.free_one();
    }
  }
  CApiDatabase(const CApiDatabase&) = delete;
  CApiDatabase& operator=(const CApiDatabase&) = delete;

  void put(int space, int owner, int id, std::span<const std::byte> bytes, int life_ms) override {
    demand_put(space, owner, id, bytes.size(), life_ms);
    void* value = const_cast<std::byte*>(bytes.data());  // the C API's pointer is not const; it only reads
    int written = -1;
    if (scope() == Scope::kOneAgent && owner == space && life_ms == 0) {
      written = api_.put_one(id, value);
    } else {
      CANHIL_DEMAND(api_.put_in != nullptr,
                    (library() + " has no DB_put_in: it writes only its own items, unaged").c_str());
      written = api_.put_in(first_space_ + space, owner, id, value, life_ms);
    }
    demand_written(written, space, owner, id);
  }

  bool puts_ranges() const noexcept override { return api_.put_ranges != nullptr; }

  void put_ranges(int space, int owner, int id, std::span<const std::byte> bytes, std::span<const ByteRange> changed,
                  int life_ms) override {
    constexpr std::size_t kMost = 16;  // the ranges of a few point lists and their counts
    if (api_.put_ranges == nullptr || changed.size() > kMost) {
      put(space, owner, id, bytes, life_ms);
      return;
    }
    demand_put(space, owner, id, bytes.size(), life_ms);
    std::array<std::size_t, 2 * kMost> flat{};
    for (std::size_t i = 0; i < changed.size(); ++i) {
      flat[2 * i] = changed[i].offset;
      flat[2 * i + 1] = changed[i].size;
    }
    const int written = api_.put_ranges(first_space_ + space, owner, id, bytes.data(), flat.data(),
                                        static_cast<int>(changed.size()), life_ms);
    demand_written(written, space, owner, id);
  }

  std::optional<int> get(int space, int owner, int id, std::span<std::byte> bytes) override {
    demand_slot(space, owner, id, bytes.size());
    const int age = raw_get(space, owner, id, bytes.data());
    if (age == -1) return std::nullopt;
    if (age < 0) return kNeverWritten;  // CAMBADA: INT_MIN (a zero time stamp overflowing)
    return age;
  }

  /// The table against the library: every item the table gives a served
  /// space is read once (and its size compared where the library can say).
  void verify() const {
    const ItemTable& t = items();
    for (const int space : spaces()) {
      if (space < 0 || space >= t.agent_count()) {
        throw SetupError(library() + " serves agent " + std::to_string(space) + ", which is not in " + t.source() +
                         " (agents 0 to " + std::to_string(t.agent_count() - 1) + "); set AGENT accordingly");
      }
    }
    // The library copies what it thinks the size is: a generous scratch.
    std::size_t biggest = 0;
    for (int id = 0; id < t.item_count(); ++id) biggest = std::max(biggest, t.size(id).value_or(0));
    std::vector<std::byte> scratch(std::max<std::size_t>(std::size_t{1} << 20, 4 * biggest));
    for (const int space : spaces()) {
      for (int owner = 0; owner < t.agent_count(); ++owner) {
        for (int id = 0; id < t.item_count(); ++id) {
          const ItemKind kind = t.kind(owner, id);
          if (owner == space ? kind == ItemKind::kNone : kind != ItemKind::kShared) continue;
          if (api_.item_size != nullptr && api_.item_size(id) != static_cast<int>(*t.size(id))) {
            throw SetupError(library() + " has item " + t.name(id) + " with " + std::to_string(api_.item_size(id)) +
                             " bytes, " + t.source() + " with " + std::to_string(*t.size(id)) +
                             ": the library reads another item table; give it the same rtdb.ini");
          }
          if (raw_get(space, owner, id, scratch.data()) == -1) {
            throw SetupError(library() + " has no " + slot_name(space, owner, id) + ", which " + t.source() +
                             " has: the library reads another item table; give it the same rtdb.ini");
          }
        }
      }
    }
  }

 private:
  int raw_get(int space, int owner, int id, void* value) const {
    return scope() == Scope::kAllAgents ? api_.get_from(first_space_ + space, owner, id, value)
                                        : api_.get_one(owner, id, value);
  }
  std::string slot_name(int space, int owner, int id) const {
    return "item " + items().name(id) + " (id " + std::to_string(id) + ") of agent " + std::to_string(owner) +
           " in agent " + std::to_string(space) + "'s database";
  }
  // What put() and put_ranges() demand of their caller, and of the library's answer.
  void demand_put(int space, int owner, int id, std::size_t size, int life_ms) const {
    demand_slot(space, owner, id, size);
    CANHIL_DEMAND(life_ms >= 0, "an RTDB item cannot be written with a negative age");
  }
  void demand_written(int written, int space, int owner, int id) const {
    CANHIL_DEMAND(written >= 0,
                  (library() + " refused " + slot_name(space, owner, id) + ", which it had at open").c_str());
  }

  CApi api_;
  std::unique_ptr<LoadedLibrary> loaded_;
  int set_ = 0;
  int first_space_ = 0;
};

// A library without Whoami: its agent is AGENT's (verify() checks it).
int agent_from_environment() {
  const char* a = std::getenv("AGENT");
  return a != nullptr ? static_cast<int>(std::strtol(a, nullptr, 10)) : -1;
}

std::vector<int> all_agents(const ItemTable& t) {
  std::vector<int> out(static_cast<std::size_t>(t.agent_count()));
  for (std::size_t a = 0; a < out.size(); ++a) out[a] = static_cast<int>(a);
  return out;
}

// SECOND_RTDB as canhil's library reads it (a one-agent Database's set).
int set_from_environment() { return canhil_second_set_from_environment() != 0 ? 1 : 0; }

void check_set(int set) {
  if (set != 0 && set != 1) {
    throw SetupError("RTDB set " + std::to_string(set) + ": a run has two teams at most (sets 0 and 1)");
  }
}

}  // namespace

Database::Database(ItemTable items, Scope scope, std::vector<int> spaces, std::string library)
    : items_(std::move(items)), scope_(scope), spaces_(std::move(spaces)), library_(std::move(library)) {
  const int agents = items_.agent_count();
  const int ids = items_.item_count();
  slot_sizes_.assign(
      static_cast<std::size_t>(agents) * static_cast<std::size_t>(agents) * static_cast<std::size_t>(ids), 0);
  for (const int space : spaces_) {
    if (space < 0 || space >= agents) continue;
    for (int owner = 0; owner < agents; ++owner) {
      for (int id = 0; id < ids; ++id) {
        const ItemKind kind = items_.kind(owner, id);
        if (owner == space ? kind == ItemKind::kNone : kind != ItemKind::kShared) continue;
        slot_sizes_[(static_cast<std::size_t>(space) * static_cast<std::size_t>(agents) +
                     static_cast<std::size_t>(owner)) *
                        static_cast<std::size_t>(ids) +
                    static_cast<std::size_t>(id)] = items_.size(id).value_or(0);
      }
    }
  }
}

Database::~Database() = default;

bool Database::serves(int space) const noexcept {
  return std::find(spaces_.begin(), spaces_.end(), space) != spaces_.end();
}

void Database::broken_slot(int space, int owner, int id, std::size_t size) const {
  CANHIL_DEMAND(serves(space), ("RTDB access to agent " + std::to_string(space) + "'s database, which " + library_ +
                                " does not reach here (check with require() at set-up)")
                                   .c_str());
  const ItemKind kind = items_.kind(owner, id);
  CANHIL_DEMAND(owner == space ? kind != ItemKind::kNone : kind == ItemKind::kShared,
                ("RTDB item " + std::to_string(id) + " of agent " + std::to_string(owner) + " is not in agent " +
                 std::to_string(space) + "'s database (check with require() at set-up)")
                    .c_str());
  CANHIL_DEMAND(items_.size(id) == size, ("RTDB item " + items_.name(id) + " accessed with " + std::to_string(size) +
                                          " bytes; it has " + std::to_string(items_.size(id).value_or(0)))
                                             .c_str());
  std::abort();  // unreachable: slot_sizes_ is built from the table the checks above read
}

int Database::require(std::string_view item, std::size_t size, int space) const {
  return require(item, size, space, space);
}

int Database::require(std::string_view item, std::size_t size, int space, int owner) const {
  const std::string name(item);
  const std::string agent = "agent " + std::to_string(owner) + " (" + items_.agent_name(owner) + ")";
  if (!serves(space)) {
    throw SetupError("RTDB item " + name + " of agent " + std::to_string(space) + " asked for, but " + library_ +
                     " is open for " + (spaces_.size() == 1 ? "agent " + std::to_string(spaces_[0]) : "other agents") +
                     " only: open it for every agent (Scope::kAllAgents) or run with AGENT=" + std::to_string(space));
  }
  const std::optional<int> id = items_.id(item);
  const std::string bytes = std::to_string(size) + " bytes";
  if (!id) {
    throw SetupError("RTDB item " + name + " is not in the team's configuration (" + items_.source() + "); add it (" +
                     bytes + ") to " + agent + "'s schema and regenerate rtdb_user.h and rtdb.ini");
  }
  if (!items_.size(*id)) {
    throw SetupError("RTDB item " + name + " (id " + std::to_string(*id) +
                     ") is in the team's rtdb_user.h but in no agent's section of its rtdb.ini (" + items_.source() +
                     "): the two files come from different configurations, or no schema uses the item; add it to " +
                     agent + "'s schema and regenerate both");
  }
  if (items_.kind(owner, *id) == ItemKind::kNone) {
    throw SetupError(agent + " has no RTDB item " + name + " in " + items_.source() +
                     "; add it to that agent's schema (shared or local) and regenerate");
  }
  if (owner != space && items_.kind(owner, *id) != ItemKind::kShared) {
    throw SetupError(agent + "'s RTDB item " + name + " is local in " + items_.source() + ", so agent " +
                     std::to_string(space) +
                     "'s database has no copy of it; share it in that agent's schema and "
                     "regenerate");
  }
  if (*items_.size(*id) != size) {
    throw SetupError("RTDB item " + name + " is " + std::to_string(*items_.size(*id)) + " bytes in " + items_.source() +
                     ", but canhil writes " + bytes + " into it: make the team's type for " + name +
                     " and canhil's layout of it agree (fix the wrong one, regenerate the team's files)");
  }
  return *id;
}

std::unique_ptr<Database> open_builtin(Scope scope, int set) {
  check_set(set);
  CApi api;
  api.init_all = &DB_init_all;
  api.free_all = &DB_free_all;
  api.put_in = &DB_put_in;
  api.put_ranges = &DB_put_ranges;
  api.get_from = &DB_get_from;
  api.init_one = &DB_init;
  api.free_one = &DB_free;
  api.put_one = &DB_put;
  api.get_one = &DB_get;
  api.whoami = &Whoami;
  api.item_size = &DB_item_size;
  api.signal_frame = &DB_signal_frame;
  api.set_clock = &DB_set_clock;
  std::vector<int> spaces;
  if (scope == Scope::kOneAgent) set = set_from_environment();
  if (scope == Scope::kAllAgents) {
    if (DB_init_all(set) != 0) {
      throw SetupError(std::string("cannot attach to canhil's RTDB") + (set == 1 ? " (the second team's set)" : "") +
                       " (the reason is above)");
    }
  } else {
    if (DB_init() != 0)
      throw SetupError("cannot attach to canhil's RTDB as this process's agent (the reason is above)");
    spaces.push_back(Whoami());
  }
  std::optional<ItemTable> table;
  try {
    table = ItemTable::builtin();
  } catch (...) {
    scope == Scope::kAllAgents ? DB_free_all(set) : DB_free();
    throw;
  }
  if (scope == Scope::kAllAgents) spaces = all_agents(*table);
  std::string library = table->source();
  return std::make_unique<CApiDatabase>(std::move(*table), scope, std::move(spaces), std::move(library), api, nullptr,
                                        set);
}

std::unique_ptr<Database> open_library(const std::filesystem::path& so, ItemTable table, Scope scope,
                                       std::optional<std::filesystem::path> config_file, int set) {
  check_set(set);
  if (scope == Scope::kOneAgent) set = set_from_environment();
  auto loaded = std::make_unique<LoadedLibrary>(so, set, config_file ? config_file->string() : std::string());
  CApi api;
  std::vector<std::string> missing;
  if (scope == Scope::kAllAgents) {
    api.init_all = loaded->symbol<int (*)(int)>("DB_init_all", &missing);
    api.free_all = loaded->symbol<void (*)(int)>("DB_free_all", &missing);
    api.put_in = loaded->symbol<int (*)(int, int, int, void*, int)>("DB_put_in", &missing);
    api.get_from = loaded->symbol<int (*)(int, int, int, void*)>("DB_get_from", &missing);
  } else {
    api.init_one = loaded->symbol<int (*)()>("DB_init", &missing);
    api.free_one = loaded->symbol<void (*)()>("DB_free", &missing);
    api.put_one = loaded->symbol<int (*)(int, void*)>("DB_put", &missing);
    api.get_one = loaded->symbol<int (*)(int, int, void*)>("DB_get", &missing);
    api.put_in = loaded->symbol<int (*)(int, int, int, void*, int)>("DB_put_in", nullptr);
    api.whoami = loaded->symbol<int (*)()>("Whoami", nullptr);
  }
  if (config_file) api.set_config_file = loaded->symbol<void (*)(const char*)>("DB_set_config_file", &missing);
  api.item_size = loaded->symbol<int (*)(int)>("DB_item_size", nullptr);
  api.put_ranges =
      loaded->symbol<int (*)(int, int, int, const void*, const std::size_t*, int, int)>("DB_put_ranges", nullptr);
  const std::string library = so.string();
  if (!missing.empty()) {
    throw SetupError(library + " has no " + join(missing) +
                     ": not an RTDB library with CAMBADA's API (every agent needs DB_init_all, DB_free_all, "
                     "DB_put_in and DB_get_from; one agent DB_init, DB_free, DB_put and DB_get" +
                     (config_file ? "; a configuration file DB_set_config_file" : "") + ")");
  }
  if (config_file && !loaded->shares_table()) api.set_config_file(config_file->c_str());
  const std::string table_file =
      config_file ? config_file->string() : "its default item table (../config/rtdb.ini from the working directory)";
  std::vector<int> spaces;
  if (scope == Scope::kAllAgents) {
    if (api.init_all(set) != 0) {
      throw SetupError("DB_init_all failed in " + library + " (its messages are above): check " + table_file +
                       (set == 1 ? " (the second team's set, DB_init_all(1))" : "") +
                       ", and that no database of another configuration is in the way");
    }
    spaces = all_agents(table);
  } else {
    if (api.init_one() != 0) {
      throw SetupError("DB_init failed in " + library +
                       " (its messages are above): set AGENT to this process's agent " + "number, and check " +
                       table_file);
    }
    spaces.push_back(api.whoami != nullptr ? api.whoami() : agent_from_environment());
  }
  auto db =
      std::make_unique<CApiDatabase>(std::move(table), scope, std::move(spaces), library, api, std::move(loaded), set);
  db->verify();  // throws after the free, by db's destruction
  return db;
}

}  // namespace canhil::rtdb
