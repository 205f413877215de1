#include "canhil/emulator/virtual_driver.hpp"

#include <algorithm>

#include "canhil/can_nodes/wire_faults.hpp"
#include "canhil/emulator/handler_participant.hpp"
#include "canhil/emulator/laptop_link.hpp"
#include "canhil/laptop/agent.hpp"
#include "canhil/laptop/agent_io.hpp"

namespace canhil::emulator {
namespace {

// The reference agent, woken after each of its vision frames.
class AgentParticipant final : public can_nodes::Participant {
 public:
  AgentParticipant(LaptopLink& link, int agent, const laptop::AgentConfig& config)
      : io_(link.database(), link.layout(), agent), logic_(config) {}
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

}  // namespace

struct VirtualDriver::ReferenceStack {
  std::unique_ptr<HandlerParticipant> handler;
  std::unique_ptr<AgentParticipant> agent;
  std::uint32_t placements = 0;  // the referee's, answered so far
};

VirtualDriver::VirtualDriver(Session& session, VirtualOptions options)
    : session_(session),
      options_(options),
      watch_(session, {options.record_trace, options.check_timing}),
      time_(clock_) {
  if (options_.reference_handler_and_agent && !session_.options().vision_on) {
    throw SetupError("the reference laptop stack needs the vision and the RTDB (SessionOptions::vision_on)");
  }
  if (session_.scenario().mixes_real_boards() && !options_.caller_plays_real_boards) {
    throw SetupError(
        "emulate = [...] leaves nodes to real boards, and a virtual-time run has no real bus: run that "
        "scenario in real time (without --virtual-time)");
  }
  if (options_.reference_handler_and_agent) {
    // Items stamped and aged in the run's time: an age is what the robot would see, at any speed.
    session_.for_each_laptop([this](LaptopLink& link) { rtdb_clock_set_ |= link.set_clock(&virtual_now, &clock_); });
  }
  const std::size_t n = session_.robot_count();
  const BusPhysics& physics = session_.options().bus;
  for (std::size_t r = 0; r < n; ++r) {
    buses_.push_back(std::make_unique<can_nodes::MemoryBus>(clock_, session_.rig(r).interface));
    if (physics.timed()) {
      // The robot's wire: every node and the handler a controller on it (docs/wire.md).
      buses_.back()->set_wire(physics.wire(session_.scenario().seed + r));
      time_.add(buses_.back()->wire_participant());
    }
  }
  controllers_.resize(n);
  session_.build_nodes(
      [this](std::size_t r, const std::string& node) {
        auto endpoint = buses_[r]->attach(node);
        if (buses_[r]->wire_bus() != nullptr) {
          controllers_[r][can_nodes::fault_node_name(node)] = buses_[r]->controller_of(*endpoint);
        }
        return std::unique_ptr<can_nodes::Endpoint>(std::move(endpoint));
      },
      Session::IoMode::kDirect, Nanos{0});
  laptop::AgentConfig agent_cfg;
  agent_cfg.kick_power = session_.scenario().kick_power;
  const auto& messages = session_.options().messages;
  const Nanos ec = session_.options().ftt.elementary_cycle;
  for (std::size_t r = 0; r < n; ++r) {
    const Rig& rig = session_.rig(r);
    auto stack = std::make_unique<ReferenceStack>();
    if (options_.reference_handler_and_agent) {
      // A fresh database: every item of the agent zeroed, the handler asked
      // to put the odometry where the robot stands.
      LaptopLink& link = *session_.laptop(rig.team);
      link.clear_items(rig.in_team);
      try {
        link.place(rig.in_team, session_.world().robot(r).pose());
      } catch (const SetupError& e) {
        throw SetupError(std::string("the in-process reference laptop tells its handler where the robot starts "
                                     "(CMD_SETPOSE): ") +
                         e.what());
      }
      stack->handler = std::make_unique<HandlerParticipant>(*buses_[r], messages, ec, clock_, link.database(),
                                                            link.layout(), rig.agent);
      stack->handler->hw().set_bit_rate(session_.options().ftt.bit_rate);
      stack->handler->hw().set_stamps(session_.options().ftt.stamps);
      stack->handler->set_fault_hook(rig.faults.get());  // rules naming `laptop` or its messages
      if (buses_[r]->wire_bus() != nullptr) {
        controllers_[r][can_nodes::kLaptopTarget] = buses_[r]->controller_of(stack->handler->endpoint());
      }
      const double goal_x = session_.scenario().world.field.length_m / 2;
      agent_cfg.goal_x_m = session_.scenario().teams[rig.team].attacks_positive_x ? goal_x : -goal_x;
      stack->agent = std::make_unique<AgentParticipant>(link, rig.agent, agent_cfg);
    }
    if (options_.count_frames || options_.record_trace || options_.check_timing) {
      // Every frame as the bus carries it, error frames included (they belong in the trace).
      listening_ = true;
      buses_[r]->set_tap([this, r](const frames::TimedFrame& f) { watch_.add(r, f); });
    }
    stacks_.push_back(std::move(stack));
  }
  // Ticked in this order at every instant: robot by robot, its nodes, then its handler and agent.
  for (std::size_t r = 0; r < n; ++r) {
    for (can_nodes::Node* node : session_.rig(r).nodes->nodes()) time_.add(*node);
    if (stacks_[r]->handler) time_.add(*stacks_[r]->handler);
    if (stacks_[r]->agent) time_.add(*stacks_[r]->agent);
  }
  if (physics.timed()) {
    add_wire_faults(session_.scenario().faults);
    session_.on_wire_fault([this](const can_nodes::FaultRule& rule) { add_wire_faults({rule}); });
  }
  session_.on_detail([this](WorldSnapshot& s) { fill_detail(s); });
  session_.on_vision_frame([this](std::size_t r, Nanos now) {
    if (stacks_[r]->agent) stacks_[r]->agent->frame_ready(now);
  });
  time_.set_step(session_.step_period(), [this](Nanos now) {
    session_.step(now);
    if (options_.reference_handler_and_agent) set_pose_of_carried_robots();
  });
}

// The reference agent knows where it is only from the odometry: a robot the
// referee carried is told its new place, as at the start (a team's own agent
// is told to find itself again from what its camera sees: COACH_INFO's
// relocations, Session).
void VirtualDriver::set_pose_of_carried_robots() {
  for (std::size_t r = 0; r < stacks_.size(); ++r) {
    ReferenceStack& l = *stacks_[r];
    const std::uint32_t placed = session_.referee_placements(r);
    if (placed == l.placements || !l.handler) continue;
    l.placements = placed;
    const Rig& rig = session_.rig(r);
    session_.laptop(rig.team)->place(rig.in_team, session_.world().robot(r).pose());
  }
}

void VirtualDriver::add_wire_faults(const std::vector<can_nodes::FaultRule>& rules) {
  for (std::size_t r = 0; r < buses_.size(); ++r) {
    const auto& named = controllers_[r];
    const can_nodes::ControllerOf controller_of = [&named](std::string_view node) -> std::optional<wire::ControllerId> {
      const auto it = named.find(node);
      if (it == named.end()) return std::nullopt;
      return it->second;
    };
    for (const wire::FaultRule& w : can_nodes::wire_rules(rules, *session_.options().messages, controller_of)) {
      buses_[r]->wire_bus()->add_fault(w);
    }
  }
}

VirtualDriver::~VirtualDriver() {
  for (auto& bus : buses_) bus->set_tap({});  // what is sent as the nodes go down is no longer this run's
  session_.on_vision_frame(nullptr);
  session_.on_detail(nullptr);
  session_.on_wire_fault(nullptr);
  if (rtdb_clock_set_) session_.for_each_laptop([](LaptopLink& link) { link.set_clock(nullptr, nullptr); });
}

void VirtualDriver::run_until(Nanos end) { time_.run_until(end); }

void VirtualDriver::run_for(Nanos duration) { run_until(clock_.now() + duration); }

std::uint64_t VirtualDriver::ftt_violations(std::size_t robot) const { return watch_.ftt_violations(robot); }

std::uint64_t VirtualDriver::trace_hash() const noexcept { return watch_.trace_hash(); }

void VirtualDriver::fill_detail(WorldSnapshot& s) {
  if (!listening_) return;  // no listener on the buses: nothing measured
  watch_.fill(s.buses, clock_.now());
  for (std::size_t r = 0; r < s.buses.size(); ++r) {
    BusDetail& b = s.buses[r];
    b.handler_latency_ms.reset();
    if (const laptop::HwComm* h = handler(r); h != nullptr && !h->stats().latencies.empty()) {
      b.handler_latency_ms = to_ms(h->stats().latencies.back());
    }
  }
}

const laptop::HwComm* VirtualDriver::handler(std::size_t robot) const {
  const auto& h = stacks_.at(robot)->handler;
  return h ? &h->hw() : nullptr;
}

std::vector<RobotOutcome> VirtualDriver::outcomes() const {
  std::vector<RobotOutcome> out;
  const physics::World& world = session_.world();
  for (std::size_t r = 0; r < session_.robot_count(); ++r) {
    RobotOutcome o;
    o.pose = world.robot(r).pose();
    o.kicks = stacks_[r]->agent ? stacks_[r]->agent->kicks() : 0;
    o.frames = watch_.frames(r);
    o.bad_frames = session_.rig(r).nodes->bad_frames();
    o.battery = world.robot(r).battery();
    o.charge = world.robot(r).charge();
    out.push_back(o);
  }
  return out;
}

std::string VirtualDriver::trace() const { return watch_.trace(); }

}  // namespace canhil::emulator
