// Masters: the counting both implementations share, canhil's own PMan
// through its handle API, and the read-only view of every table.
#include "canhil/pman/masters.hpp"

#include <sys/ipc.h>
#include <sys/shm.h>

#include <climits>
#include <map>

#include "canhil/base/setup_error.hpp"
#include "canhil/pman/pman_master.h"
#include "masters_common.hpp"

namespace canhil::pman {

bool Process::idle() const noexcept { return status == PROC_S_IDLE && last_finish_us >= last_start_us; }

Process process_of(const PROC_TYPE& p) {
  Process out;
  out.name.assign(p.PROC_name, strnlen(p.PROC_name, sizeof p.PROC_name));
  out.pid = p.PROC_id;
  out.status = p.PROC_status;
  out.activations = p.PROC_nact;
  out.last_start_us = static_cast<std::int64_t>(p.PROC_last_start.tv_sec) * 1'000'000 + p.PROC_last_start.tv_usec;
  out.last_finish_us = static_cast<std::int64_t>(p.PROC_last_finish.tv_sec) * 1'000'000 + p.PROC_last_finish.tv_usec;
  return out;
}

bool Masters::all_idle(int agent) {
  for (const Process& p : query(agent)) {
    if (p.pid != 0 && !p.idle()) return false;
  }
  return true;
}

int CountingMasters::tick(int agent) {
  Book& book = books_[agent];
  // The activations of the last tick: ended by now (an epilogue) or not (a miss).
  const std::vector<Process> before = query(agent);
  for (const Process& p : before) {
    ProcessCounts& c = book.counts[p.name];
    if (!book.pending[p.name]) continue;
    book.pending[p.name] = false;
    if (p.idle()) {
      ++c.epilogues;
    } else {
      ++c.deadline_misses;
    }
  }
  do_tick(agent);
  int signalled = 0;
  for (const Process& p : query(agent)) {
    const auto old = std::find_if(before.begin(), before.end(), [&](const Process& b) { return b.name == p.name; });
    if (old != before.end() && old->pid != 0 && p.pid == 0) ++book.counts[p.name].gone;  // died, or left
    if (old != before.end() && p.activations > old->activations) {
      ++book.counts[p.name].activations;
      book.pending[p.name] = true;
      ++signalled;
    }
  }
  return signalled;
}

std::vector<ProcessCounts> CountingMasters::counts(int agent) const {
  std::vector<ProcessCounts> out;
  const auto it = books_.find(agent);
  if (it == books_.end()) return out;
  for (const auto& [name, c] : it->second.counts) {
    ProcessCounts copy = c;
    copy.name = name;
    out.push_back(copy);
  }
  return out;
}

void CountingMasters::registered(int agent, const std::vector<std::string>& names) {
  Book& book = books_[agent];
  for (const std::string& n : names) book.counts[n].name = n;
}

namespace {

class BuiltinMasters final : public CountingMasters {
 public:
  explicit BuiltinMasters(int set) : set_(set) {}
  ~BuiltinMasters() override { BuiltinMasters::close_all(); }

  void open(int agent, const std::vector<std::string>& processes) override {
    int error = PMAN_E_AGENT;
    const long long key = CANHIL_PMAN_SET_KEY(static_cast<long long>(set_), static_cast<long long>(agent));
    canhil_pman* h = agent < 0 || key > INT_MAX
                         ? nullptr
                         : canhil_pman_open_master_keys(static_cast<key_t>(key), static_cast<key_t>(key), &error);
    if (h == nullptr) {
      throw SetupError("cannot create robot " + std::to_string(agent) + "'s PMan table (key 0x" +
                       hex(static_cast<int>(key)) + ", error " + std::to_string(error) +
                       "): is another PMan master (an omni vision, another canhil) running for this agent? "
                       "`canhil pman list` shows the tables");
    }
    tables_[agent] = Table{h, processes};
    for (const std::string& name : processes) {
      const int r = canhil_pman_procadd(h, name.c_str(), 1, 0, 10000);
      if (r != 0) {
        throw SetupError("cannot register \"" + name + "\" in robot " + std::to_string(agent) + "'s PMan table (" +
                         std::to_string(r) + "); names are 1 to 32 characters, each once, at most 20");
      }
    }
    canhil_pman_start(h);
    registered(agent, processes);
  }

  std::vector<Process> query(int agent) override {
    std::vector<Process> out;
    const auto it = tables_.find(agent);
    if (it == tables_.end()) return out;
    for (const std::string& name : it->second.names) {
      PROC_TYPE p{};
      if (canhil_pman_query(it->second.handle, name.c_str(), &p) == 0) out.push_back(process_of(p));
    }
    return out;
  }

  void close_all() override {
    for (auto& [agent, t] : tables_) canhil_pman_close(t.handle);
    tables_.clear();
  }

  std::string description() const override {
    return set_ == 0 ? "canhil's own PMan" : "canhil's own PMan, the second team's keys";
  }

 private:
  void do_tick(int agent) override {
    const auto it = tables_.find(agent);
    if (it != tables_.end()) canhil_pman_tick(it->second.handle);
  }
  struct Table {
    canhil_pman* handle = nullptr;
    std::vector<std::string> names;
  };
  std::map<int, Table> tables_;
  int set_;
};

}  // namespace

std::string hex(int key) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%X", static_cast<unsigned>(key));
  return buf;
}

std::unique_ptr<Masters> builtin_masters(int set) {
  if (set != 0 && set != 1) throw SetupError("a PMan key set is 0 (the first team) or 1 (the second)");
  return std::make_unique<BuiltinMasters>(set);
}

std::vector<TableView> read_tables(int first_agent, int last_agent) {
  std::vector<TableView> out;
  for (int set = 0; set < 2; ++set) {
    for (int agent = first_agent; agent <= last_agent; ++agent) {
      const int key = CANHIL_PMAN_SET_KEY(set, agent);
      const int id = shmget(key, 0, 0);
      if (id < 0) continue;
      shmid_ds ds{};
      if (shmctl(id, IPC_STAT, &ds) != 0 || ds.shm_segsz < sizeof(PROC_TABLE_TYPE)) continue;  // not a table
      void* at = shmat(id, nullptr, SHM_RDONLY);
      if (at == reinterpret_cast<void*>(-1)) continue;  // NOLINT(performance-no-int-to-ptr): shmat's error value
      const auto* table = static_cast<const PROC_TABLE_TYPE*>(at);
      TableView view;
      view.agent = agent;
      view.set = set;
      view.key = key;
      view.ticks = table->ticks < 0 ? 0 : static_cast<std::uint64_t>(table->ticks);
      for (const PROC_TYPE& p : table->proc) {  // read as untrusted: only what fits
        if (p.PROC_name[0] != '\0') view.processes.push_back(process_of(p));
      }
      shmdt(at);
      out.push_back(std::move(view));
    }
  }
  return out;
}

}  // namespace canhil::pman
