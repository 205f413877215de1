#include "canhil/emulator/virtual_driver.hpp"

#include "canhil/emulator/laptop_link.hpp"

#include <algorithm>

#include "canhil/emulator/handler_participant.hpp"
#include "canhil/laptop/agent.hpp"
#include "canhil/laptop/agent_io.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "merged_trace.hpp"
#include "rtdb_user.h"

namespace canhil::emulator {
namespace {

// The reference agent, woken after each of its vision frames.
class AgentParticipant final : public can_nodes::Participant {
 public:
  AgentParticipant(int space, const laptop::AgentConfig& config) : io_(space), logic_(config) {}
  void frame_ready(Nanos now) { wake_ = now; }
  std::size_t poll() override { return 0; }
  bool may_have_frames() const override { return false; }
  bool set_doorbell(const std::shared_ptr<can_nodes::Doorbell>& /*bell*/, std::size_t /*index*/) override {
    return true;
  }  // reads no bus
  /// Woken by the vision frames of the physics step (the runner's periodic step).
  bool wakeup_is_own() const override { return true; }
  Nanos next_wakeup() const override { return wake_; }
  void tick(Nanos now) override {
    wake_ = kNever;
    const double dt = last_ == kNever ? 1.0 / 30 : to_seconds(now - last_);
    last_ = now;
    io_.write(logic_.decide(io_.read(dt)));
  }
  int kicks() const { return logic_.kicks(); }

 private:
  laptop::AgentIo io_;
  laptop::Agent logic_;
  Nanos wake_ = kNever;
  Nanos last_ = kNever;
};

// The RTDB's clock during a run: the run's virtual time.
std::int64_t virtual_now(void* clock) { return static_cast<const can_nodes::SimulatedClock*>(clock)->now().count(); }

// A fresh database for the run: every item of the agent zeroed, and the
// handler asked to put the odometry where the robot stands.
// `space` is the agent's memory space (its team's set).
void prepare_rtdb(int space, int agent, const kinematics::Pose& at) {
  for (int item = 0; item < DB_item_count(); ++item) {
    if (DB_item_shared(agent, item) < 0) continue;
    std::vector<unsigned char> zero(static_cast<std::size_t>(DB_item_size(item)), 0);
    DB_put_in(space, agent, item, zero.data(), 0);
  }
  CMD_SetPose pose{static_cast<float>(at.x_m), static_cast<float>(at.y_m), static_cast<float>(at.heading_rad), 0, 1};
  DB_put_in(space, agent, CMD_SETPOSE, &pose, 0);
}

}  // namespace

struct VirtualDriver::Laptop {
  std::unique_ptr<HandlerParticipant> handler;
  std::unique_ptr<AgentParticipant> agent;
  int space = 0;  // the agent's memory space (its team's set)
  int agent_number = 0;
  std::uint32_t placements = 0;  // the referee's, answered so far
};

VirtualDriver::VirtualDriver(Session& session, VirtualOptions options)
    : session_(session), options_(options), lockstep_(clock_) {
  if (options_.reference_laptop && !session_.options().vision_on) {
    throw SetupError("the reference laptop stack needs the vision and the RTDB (SessionOptions::vision_on)");
  }
  for (std::size_t t = 0; options_.reference_laptop && t < session_.scenario().teams.size(); ++t) {
    const LaptopSide& side = session_.scenario().laptop_of(t);
    if (side.rtdb_lib != "builtin" || side.layout != "canhil") {
      throw SetupError(
          "the in-process reference laptop (canhil's handler and agent) works on canhil's linked RTDB in canhil's "
          "layout, not on " +
          side.rtdb_lib + " in layout " + side.layout +
          "; run the team's own software against a real-time run (canhil run without --virtual-time)");
    }
  }
  if (session_.scenario().mixes_real_boards() && !options_.caller_plays_real_boards) {
    throw SetupError(
        "emulate = [...] leaves nodes to real boards, and a virtual-time run has no real bus: run that "
        "scenario in real time (without --virtual-time)");
  }
  if (options_.reference_laptop) {
    // Items stamped and aged in the run's time: an age is what the robot would see, at any speed.
    DB_set_clock(&virtual_now, &clock_);
    rtdb_clock_set_ = true;
  }
  const std::size_t n = session_.robot_count();
  for (std::size_t r = 0; r < n; ++r) {
    buses_.push_back(std::make_unique<can_nodes::MemoryBus>(clock_, session_.rig(r).interface));
  }
  session_.build_nodes(
      [this](std::size_t r, const std::string& node) {
        return std::unique_ptr<can_nodes::Bus>(buses_[r]->attach(node));
      },
      Session::IoMode::kDirect, Nanos{0});
  laptop::AgentConfig agent_cfg;
  agent_cfg.kick_power = session_.scenario().kick_power;
  const auto& messages = session_.options().messages;
  const Nanos ec = session_.options().ftt.elementary_cycle;
  recorded_.resize(n);
  frame_counts_.resize(n);
  for (std::size_t r = 0; r < n; ++r) {
    const Rig& rig = session_.rig(r);
    auto laptop = std::make_unique<Laptop>();
    if (options_.reference_laptop) {
      // The team's set of canhil's databases: its agents' memory spaces follow the first set's.
      const int space = static_cast<int>(rig.team) * DB_agent_count() + rig.agent;
      prepare_rtdb(space, rig.agent, session_.world().robot(r).pose());
      laptop->space = space;
      laptop->agent_number = rig.agent;
      LaptopLink& link = *session_.laptop(rig.team);
      laptop->handler = std::make_unique<HandlerParticipant>(*buses_[r], messages, ec, clock_, link.database(),
                                                             link.layout(), rig.agent);
      const double goal_x = session_.scenario().world.field.length_m / 2;
      agent_cfg.goal_x_m = session_.scenario().teams[rig.team].attacks_positive_x ? goal_x : -goal_x;
      laptop->agent = std::make_unique<AgentParticipant>(space, agent_cfg);
    }
    if (options_.check_timing) checkers_.push_back(ftt_checker(session_.options()));
    if (options_.count_frames || options_.record_trace || options_.check_timing) {
      // Every frame as the bus carries it, error frames included (they belong in the trace).
      listening_ = true;
      buses_[r]->set_tap([this, r](const frames::TimedFrame& f) { record(r, f); });
    }
    laptops_.push_back(std::move(laptop));
  }
  // Ticked in this order at every instant: robot by robot, its nodes, then its handler and agent.
  for (std::size_t r = 0; r < n; ++r) {
    for (can_nodes::Node* node : session_.rig(r).nodes->nodes()) lockstep_.add(*node);
    if (laptops_[r]->handler) lockstep_.add(*laptops_[r]->handler);
    if (laptops_[r]->agent) lockstep_.add(*laptops_[r]->agent);
  }
  session_.on_detail([this](WorldSnapshot& s) { fill_detail(s); });
  session_.on_vision_frame([this](std::size_t r, Nanos now) {
    if (laptops_[r]->agent) laptops_[r]->agent->frame_ready(now);
  });
  lockstep_.set_step(session_.step_period(), [this](Nanos now) {
    session_.step(now);
    if (options_.reference_laptop) set_pose_of_carried_robots();
  });
}

// The reference agent knows where it is only from the odometry: a robot the
// referee carried is told its new place, as at the start (a team's own agent
// localises itself from what its camera sees).
void VirtualDriver::set_pose_of_carried_robots() {
  for (std::size_t r = 0; r < laptops_.size(); ++r) {
    Laptop& l = *laptops_[r];
    const std::uint32_t placed = session_.referee_placements(r);
    if (placed == l.placements || !l.handler) continue;
    l.placements = placed;
    const kinematics::Pose at = session_.world().robot(r).pose();
    CMD_SetPose pose{static_cast<float>(at.x_m), static_cast<float>(at.y_m), static_cast<float>(at.heading_rad), 0, 1};
    DB_put_in(l.space, l.agent_number, CMD_SETPOSE, &pose, 0);
  }
}

VirtualDriver::~VirtualDriver() {
  for (auto& bus : buses_) bus->set_tap({});  // what is sent as the nodes go down is no longer this run's
  session_.on_vision_frame(nullptr);
  session_.on_detail(nullptr);
  if (rtdb_clock_set_) DB_set_clock(nullptr, nullptr);
}

void VirtualDriver::run_until(Nanos end) { lockstep_.run_until(end); }

void VirtualDriver::run_for(Nanos duration) { run_until(clock_.now() + duration); }

void VirtualDriver::record(std::size_t r, const frames::TimedFrame& f) {
  ++frame_counts_[r];
  if (!bus_stats_.empty()) bus_stats_[r].add(f);
  if (!checkers_.empty()) checkers_[r].add(f);
  if (options_.record_trace) recorded_[r].push_back(f);
}

std::uint64_t VirtualDriver::ftt_violations(std::size_t robot) const {
  return robot < checkers_.size() ? checkers_[robot].violation_count() : 0;
}

void VirtualDriver::fill_detail(WorldSnapshot& s) {
  if (!listening_) return;  // no listener on the buses: nothing measured
  if (bus_stats_.empty()) {
    for (std::size_t r = 0; r < session_.robot_count(); ++r) {
      bus_stats_.emplace_back(session_.options().messages, session_.options().ftt.bit_rate);
    }
  }
  s.buses.resize(bus_stats_.size());
  for (std::size_t r = 0; r < bus_stats_.size(); ++r) {
    timing::LiveBusStats& stats = bus_stats_[r];
    stats.advance(clock_.now());
    BusDetail& b = s.buses[r];
    b.frames = frame_counts_[r];
    b.load = stats.load();
    b.jitter_ms = stats.jitter_ms();
    b.handler_latency_ms.reset();
    if (const laptop::HwComm* h = handler(r); h != nullptr && !h->stats().latencies.empty()) {
      b.handler_latency_ms = to_ms(h->stats().latencies.back());
    }
  }
}

const laptop::HwComm* VirtualDriver::handler(std::size_t robot) const {
  const auto& h = laptops_.at(robot)->handler;
  return h ? &h->hw() : nullptr;
}

std::vector<RobotOutcome> VirtualDriver::outcomes() const {
  std::vector<RobotOutcome> out;
  const physics::World& world = session_.world();
  for (std::size_t r = 0; r < session_.robot_count(); ++r) {
    RobotOutcome o;
    o.pose = world.robot(r).pose();
    o.kicks = laptops_[r]->agent ? laptops_[r]->agent->kicks() : 0;
    o.frames = frame_counts_[r];
    o.bad_frames = session_.rig(r).nodes->bad_frames();
    o.battery = world.robot(r).battery();
    o.charge = world.robot(r).charge();
    out.push_back(o);
  }
  return out;
}

std::string VirtualDriver::trace() const {
  std::vector<std::string> names;
  for (std::size_t r = 0; r < session_.robot_count(); ++r) names.push_back(session_.rig(r).interface);
  return merged_trace(recorded_, names);
}

}  // namespace canhil::emulator
