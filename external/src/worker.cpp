// One worker of a parallel `canhil match --external` (worker.hpp).
#include "canhil/external/worker.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "canhil/base/process.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/base/start_again.hpp"
#include "canhil/external/own_ipc.hpp"
#include "canhil/userbus/bus_hook.h"

namespace canhil::external {

namespace {

// The folders of workers' buses whose worker is gone (killed, so it could not
// remove its own): `<folder>-worker-<pid>`, this user's, the pid not running.
void remove_orphan_buses(const std::string& folder) {
  const std::filesystem::path base(folder);
  for_each_left_by_the_dead(base.parent_path(), base.filename().string() + "-worker-", '\0',
                            [](const std::filesystem::path& bus) {
                              std::error_code ignored;
                              if (std::filesystem::is_directory(std::filesystem::symlink_status(bus, ignored))) {
                                std::filesystem::remove_all(bus, ignored);
                              }
                            });
}

}  // namespace

void prepare_external_workers() {
  remove_orphan_buses(userbus::BusPaths::current().folder);
  if (userbus::hooks().loaded()) return;  // on the user-space bus already
  std::string preload;
  try {
    preload = userbus::find_preload();
  } catch (const userbus::BusError& e) {
    throw SetupError(std::string("--external with --jobs gives each match a user-space bus of its own, and ") +
                     e.what() + "; or leave --jobs out");
  }
  preload_first(preload);
}

ExternalWorker::ExternalWorker(const std::vector<std::string>& interfaces) {
  const IpcWay way = enter_own_ipc_namespace();
  try {
    const std::string folder = userbus::BusPaths::current().folder + "-worker-" + std::to_string(getpid());
    setenv("CANHIL_BUS_DIR", folder.c_str(), 1);
    paths_ = userbus::BusPaths::current();
  } catch (const userbus::BusError& e) {
    throw SetupError(std::string("a match worker's own bus: ") + e.what());
  }
  try {
    userbus::BrokerOptions options;
    options.owner = getpid();  // a worker killed in a match takes its bus with it
    userbus::start_broker(paths_, options);
    userbus::add_interfaces(paths_, interfaces);
  } catch (const userbus::BusError& e) {
    userbus::stop_broker(paths_);  // nothing when none started
    std::error_code ignored;
    std::filesystem::remove_all(paths_.folder, ignored);
    throw SetupError(std::string("a match worker's own bus: ") + e.what());
  }
  std::error_code unread;
  const std::string ns = std::filesystem::read_symlink("/proc/self/ns/ipc", unread).string();
  std::fprintf(stderr, "canhil: a worker (pid %d) on a bus of its own at %s, in an IPC namespace of its own (%s%s)\n",
               static_cast<int>(getpid()), paths_.folder.c_str(), ns.c_str(),
               way == IpcWay::kUserNamespace ? ", inside a user namespace" : "");
}

void ExternalWorker::next_match() { enter_own_ipc_namespace(); }

ExternalWorker::~ExternalWorker() {
  userbus::stop_broker(paths_);
  std::error_code ignored;
  std::filesystem::remove(paths_.folder, ignored);  // empty once the broker is gone
}

}  // namespace canhil::external
