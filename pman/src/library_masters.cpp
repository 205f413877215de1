// Masters on a team's PMan library (CAMBADA's API), loaded at run time.
//
// CAMBADA's library keeps one current table in process globals (p_table,
// pman_sem_id, pman_shmem_id); its pman_save_ids / pman_switch_id are inline
// helpers in its header, so canhil does what they do: after creating robot
// N's table it saves the three globals, and switches them back in before
// every call for that robot. PMAN_init2(PMAN_NEW) also tries to make the
// calling thread SCHED_FIFO at the top priority; canhil puts the thread's
// scheduling back as it was (a master inside canhil must not take over a
// core).
#include <dlfcn.h>
#include <pthread.h>
#include <sched.h>

#include <map>

#include "canhil/base/setup_error.hpp"
#include "canhil/pman/pman_master.h"
#include "masters_common.hpp"

namespace canhil::pman {
namespace {

extern "C" int canhil_no_qos(int) { return 0; }  // the QoS function the library may call in PMAN_tick

class LibraryMasters final : public CountingMasters {
 public:
  explicit LibraryMasters(const std::filesystem::path& so) : path_(so.string()) {
    handle_ = dlopen(path_.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle_ == nullptr) {
      throw SetupError("cannot load the PMan library " + path_ + ": " + dlerror() +
                       "; give the path of the team's libpman.so (--pman-lib)");
    }
    init2_ = symbol<Init2>("PMAN_init2");
    procadd_ = symbol<Procadd>("PMAN_procadd");
    tick_ = symbol<Tick>("PMAN_tick");
    query_ = symbol<Query>("PMAN_query");
    close_ = symbol<Close>("PMAN_close");
    p_table_ = symbol<PROC_TABLE_TYPE**>("p_table");
    sem_id_ = symbol<int*>("pman_sem_id");
    shmem_id_ = symbol<int*>("pman_shmem_id");
  }
  ~LibraryMasters() override {
    LibraryMasters::close_all();
    dlclose(handle_);
  }

  void open(int agent, const std::vector<std::string>& processes) override {
    const key_t key = CANHIL_PMAN_AGENT_KEY(agent);
    int policy = sched_getscheduler(0);
    sched_param param{};
    sched_getparam(0, &param);
    *p_table_ = nullptr;
    const int r = init2_(key, key, reinterpret_cast<void*>(&canhil_no_qos), sizeof(int), PMAN_NEW);
    sched_setscheduler(0, policy, &param);  // the library's SCHED_FIFO attempt undone
    // -15: SCHED_FIFO refused (not root), after the table was made: usable.
    if (r != 0 && r != -15) {
      throw SetupError("the PMan library " + path_ + " could not create robot " + std::to_string(agent) +
                       "'s table (key 0x" + hex(key) + ", PMAN_init2 returned " + std::to_string(r) +
                       "): is another master running for this agent? `canhil pman list` shows the tables");
    }
    Ids& ids = tables_[agent];
    ids = Ids{*p_table_, *sem_id_, *shmem_id_, processes};
    for (const std::string& name : processes) {
      int prio = 0;
      const int a = procadd_(name.c_str(), 0, 1, 0, 10000, &prio, sizeof prio);
      if (a != 0) {
        throw SetupError("the PMan library refused to register \"" + name + "\" for robot " + std::to_string(agent) +
                         " (" + std::to_string(a) + ")");
      }
    }
    registered(agent, processes);
  }

  std::vector<Process> query(int agent) override {
    std::vector<Process> out;
    if (!use(agent)) return out;
    PROC_TYPE p{};
    for (int r = query_(&p, 1); r == 0; r = query_(&p, 0)) out.push_back(process_of(p));
    return out;
  }

  void close_all() override {
    for (auto& [agent, ids] : tables_) {
      use(agent);
      close_(PMAN_CLFREE);
    }
    tables_.clear();
    *p_table_ = nullptr;
  }

  std::string description() const override { return path_; }

 private:
  using Init2 = int (*)(key_t, key_t, void*, int, int);
  using Procadd = int (*)(const char*, int, int, int, int, void*, int);
  using Tick = int (*)();
  using Query = int (*)(PROC_TYPE*, int);
  using Close = int (*)(int);
  struct Ids {
    PROC_TABLE_TYPE* table = nullptr;
    int sem = -1, shmem = -1;
    std::vector<std::string> names;
  };

  template <class T>
  T symbol(const char* name) {
    void* s = dlsym(handle_, name);
    if (s == nullptr) {
      throw SetupError("the PMan library " + path_ + " has no " + name +
                       "; canhil needs CAMBADA's PMan API (pman.h) from it");
    }
    return reinterpret_cast<T>(s);
  }
  // Robot `agent`'s table becomes the library's current one (pman_switch_id).
  bool use(int agent) {
    const auto it = tables_.find(agent);
    if (it == tables_.end()) return false;
    *p_table_ = it->second.table;
    *sem_id_ = it->second.sem;
    *shmem_id_ = it->second.shmem;
    return true;
  }
  void do_tick(int agent) override {
    if (use(agent)) tick_();
  }

  std::string path_;
  void* handle_ = nullptr;
  Init2 init2_ = nullptr;
  Procadd procadd_ = nullptr;
  Tick tick_ = nullptr;
  Query query_ = nullptr;
  Close close_ = nullptr;
  PROC_TABLE_TYPE** p_table_ = nullptr;
  int* sem_id_ = nullptr;
  int* shmem_id_ = nullptr;
  std::map<int, Ids> tables_;
};

}  // namespace

std::unique_ptr<Masters> library_masters(const std::filesystem::path& shared_object) {
  return std::make_unique<LibraryMasters>(shared_object);
}

}  // namespace canhil::pman
