#include "canhil/emulator/realtime_driver.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

#include "canhil/emulator/fifo_scheduling.hpp"
#include "canhil/emulator/laptop_link.hpp"

namespace canhil::emulator {
namespace {

// A network device with a `device` link is hardware (a CAN adapter); vcan has none.
bool is_virtual_interface(const std::string& iface) {
  return !std::filesystem::exists("/sys/class/net/" + iface + "/device");
}

}  // namespace

struct RealtimeDriver::Locked {
  explicit Locked(bool on) : lock(on) {}
  MemoryLock lock;
};

RealtimeDriver::RealtimeDriver(Session& session, RealtimeOptions options)
    : session_(session), options_(options), physics_(session, clock_, options.max_behind) {
  const std::size_t n = session_.robot_count();
  const Scenario& sc = session_.scenario();
  const bool error_frames = std::any_of(sc.faults.begin(), sc.faults.end(), [](const can_nodes::FaultRule& f) {
    return f.kind == can_nodes::FaultKind::kErrorFrame;
  });
  for (std::size_t r = 0; r < n; ++r) {
    if (is_virtual_interface(sc.interfaces[r])) continue;
    // A controller cannot be told to send an error frame: the flag would be masked and a data frame go out.
    const std::string why = "error-frame faults need a virtual interface; " + sc.interfaces[r] +
                            " is a CAN adapter. Use a bus disturber on a real bus, or run on vcan";
    if (error_frames) throw SetupError(why);
    session_.refuse_error_frames(why);
  }
  const Nanos ec = session_.options().ftt.elementary_cycle;
  start_ = (clock_.now() / ec + 10) * ec;  // on a whole EC, a little ahead
  // Per robot: a socket per emulated node in NodeId order, the system monitor's watching one last (null: a real
  // board's, or no monitor).
  sockets_.assign(n, std::vector<can_nodes::SocketCanBus*>(can_nodes::kNodeCount + 1, nullptr));
  can_nodes::SocketCanOptions socket_options;
  socket_options.receive_buffer_bytes = options_.receive_buffer_bytes;
  const BusPhysics& physics = session_.options().bus;
  for (std::size_t r = 0; r < n; ++r) {
    media_.push_back(std::make_unique<can_nodes::SocketCanMedium>(session_.rig(r).interface, socket_options));
    // The same interface twice (robots sharing a bus) is given its wire once.
    const bool given = std::any_of(media_.begin(), media_.end() - 1, [&](const auto& m) {
      return m->interface() == media_.back()->interface() && wired_[static_cast<std::size_t>(&m - &media_[0])] != 0;
    });
    // Undone at the end only where the interface was instant before the run.
    const bool had_wire = media_.back()->counts().timed;
    wired_.push_back(physics.timed() && !had_wire && (given || media_.back()->set_wire(physics.wire(sc.seed + r))) ? 1
                                                                                                                   : 0);
  }
  session_.build_nodes(
      [this](std::size_t r, const std::string& node) {
        auto bus = media_[r]->open_socket();
        const auto id = can_nodes::node_by_name(node);
        sockets_[r][id ? static_cast<std::size_t>(*id) : can_nodes::kNodeCount] = bus.get();
        return std::unique_ptr<can_nodes::Endpoint>(std::move(bus));
      },
      Session::IoMode::kShared, start_);
  std::vector<int> fds;
  for (std::size_t r = 0; r < n; ++r) {
    const auto open = [](const can_nodes::SocketCanBus* s) { return s != nullptr; };
    const auto first = std::find_if(sockets_[r].begin(), sockets_[r].end(), open);
    if (first == sockets_[r].end() || (*first)->state() != can_nodes::BusState::kUp) {
      const std::string& iface = session_.rig(r).interface;
      throw SetupError(iface + " is down; bring it up with `ip link set " + iface + " up`");
    }
    states_.push_back(can_nodes::BusState::kUp);
    // The loop's sockets (not the master's): the watching one, else any; its state is read on the loop's thread.
    watched_.push_back(sockets_[r].back());
    for (std::size_t k = 1; k < sockets_[r].size(); ++k) {
      if (sockets_[r][k] == nullptr) continue;
      fds.push_back(sockets_[r][k]->fd());
      if (watched_.back() == nullptr) watched_.back() = sockets_[r][k];
    }
  }
  waiter_ = std::make_unique<WallWaiter>(fds);
  loop_ = std::make_unique<can_nodes::Realtime>(clock_, [this](Nanos d) { waiter_->wait(d); });
  masters_ = std::make_unique<can_nodes::Realtime>(clock_, [](Nanos d) { can_nodes::WallClock::sleep_until(d); });
  for (std::size_t r = 0; r < n; ++r) {
    const can_nodes::RobotNodes& nodes = *session_.rig(r).nodes;
    for (can_nodes::Node* node : session_.rig(r).nodes->nodes()) {
      if (nodes.emulates(can_nodes::NodeId::kMaster) && node == &nodes.node(can_nodes::NodeId::kMaster)) {
        masters_->add(*node);
      } else {
        loop_->add(*node);
      }
    }
  }
  loop_->on_pass([this] { session_.apply_bus_changes(); });
  // canhil's own agent waits on canhil's RTDB's frame signal; a team's agents on their PMan.
  session_.for_each_laptop([](LaptopLink& laptop) { laptop.signal_frames(true); });
}

RealtimeDriver::~RealtimeDriver() {
  stop();
  for (std::size_t r = 0; r < media_.size(); ++r) {
    if (wired_[r] != 0) media_[r]->set_wire(can_nodes::Wire{});  // instant again, as before the run
  }
  session_.for_each_laptop([](LaptopLink& laptop) { laptop.signal_frames(false); });
}

void RealtimeDriver::start() {
  if (started_) return;
  started_ = true;
  memory_ = std::make_unique<Locked>(options_.priority > 0);
  physics_.start(start_);  // before any priority: the physics thread keeps the normal scheduler
  masters_thread_ = std::thread([this] {
    const FifoScheduling fifo(options_.priority > 0 ? std::min(99, options_.priority + 1) : 0);
    masters_->run_until(kNever, masters_stop_);
  });
}

void RealtimeDriver::run_until(Nanos end, const std::atomic<bool>& stop) {
  start();
  const FifoScheduling fifo(options_.priority);
  if (!fifo.problem.empty()) priority_problem_ = fifo.problem;
  loop_->run_until(end, stop);
}

std::vector<std::pair<std::size_t, can_nodes::BusState>> RealtimeDriver::bus_state_changes() {
  std::vector<std::pair<std::size_t, can_nodes::BusState>> changes;
  for (std::size_t r = 0; r < watched_.size(); ++r) {
    if (watched_[r] == nullptr) continue;  // only the master is emulated: its thread's socket
    const can_nodes::BusState state = watched_[r]->refresh_state();
    if (state != states_[r]) {
      changes.emplace_back(r, state);
      states_[r] = state;
    }
  }
  return changes;
}

void RealtimeDriver::stop() {
  if (stopped_ || !started_) return;
  stopped_ = true;
  masters_stop_ = true;
  if (masters_thread_.joinable()) masters_thread_.join();
  physics_.stop();  // the world is this thread's again
  // A real controller, and the user-space bus (userbus/), deliver a frame
  // after its write returned; the kernel's vcan before. So the masters' last
  // trigger message may still be on its way: it is given a moment to arrive.
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  // What is still queued is read and counted, so the summary covers every frame
  // that reached the emulator (bounded: a flood may still be going on).
  for (std::size_t r = 0; r < session_.robot_count(); ++r) {
    for (can_nodes::Node* node : session_.rig(r).nodes->nodes()) node->poll(std::size_t{1} << 16);
  }
  memory_.reset();
}

}  // namespace canhil::emulator
