#include "canhil/emulator/virtual_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "canhil/emulator/handler_participant.hpp"
#include "canhil/frames/candump.hpp"
#include "canhil/laptop/agent.hpp"
#include "canhil/laptop/agent_io.hpp"
#include "canhil/laptop/hwcomm.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "canhil/vision_emu/runner.hpp"
#include "rtdb_user.h"

namespace canhil::emulator {
namespace {

// The reference agent, woken after each of its vision frames.
class AgentParticipant final : public Participant {
 public:
  AgentParticipant(int agent, const laptop::AgentConfig& config) : io_(agent), logic_(config) {}
  void frame_ready(Nanos now) { wake_ = now; }
  std::size_t poll() override { return 0; }
  Nanos next_wakeup() const override { return wake_; }
  void tick(Nanos now) override {
    wake_ = kNever;
    const double dt = last_ == kNever ? 1.0 / 30 : std::chrono::duration<double>(now - last_).count();
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

}  // namespace

// A goal: the whole ball past a goal line, between the posts, under the bar.
void GoalWatcher::step(const physics::World& world, Nanos now) {
  const Eigen::Vector3d b = world.ball_position();
  const auto& f = params_.field;
  const double r = params_.ball.radius_m;
  const bool in = std::fabs(b.x()) > f.length_m / 2 + r && std::fabs(b.y()) < f.goal.width_m / 2 &&
                  b.z() < f.goal.height_m && std::fabs(b.x()) < f.length_m / 2 + f.goal.depth_m + r;
  if (in && !in_) goals_.push_back(Goal{now, b.x() > 0});
  in_ = in;
}

struct VirtualRun::Impl {
  VirtualRunConfig config;
  can_nodes::SimulatedClock clock;
  std::unique_ptr<physics::World> world;
  std::vector<std::unique_ptr<PhysicsRobotIo>> io;
  std::vector<can_nodes::NodeParams> params;
  std::vector<std::unique_ptr<can_nodes::MemoryBus>> buses;
  std::vector<std::unique_ptr<RobotNodes>> nodes;
  std::vector<std::unique_ptr<HandlerParticipant>> handlers;
  std::vector<std::unique_ptr<AgentParticipant>> agents;
  std::vector<std::unique_ptr<can_nodes::MemoryEndpoint>> recorders;
  std::vector<std::vector<frames::TimedFrame>> recorded;  // kept only when record_trace
  std::vector<std::uint64_t> frame_counts;
  std::unique_ptr<vision_emu::VisionRunner> vision;
  std::unique_ptr<Lockstep> run;
  std::vector<std::unique_ptr<can_nodes::FaultInjector>> injectors;
  std::string world_log;
  Nanos next_log{0};
  std::unique_ptr<GoalWatcher> goals;
  bool rtdb = false;

  int agent(std::size_t r) const { return config.agents[r]; }
  void log_world(Nanos now) {
    if (config.world_log_period <= Nanos{0} || now < next_log) return;
    next_log = now + config.world_log_period;
    char buf[160];
    const Eigen::Vector3d b = world->ball_position();
    std::snprintf(buf, sizeof buf, "%.3f,%.4f,%.4f,%.4f", std::chrono::duration<double>(now).count(), b.x(), b.y(),
                  b.z());
    world_log += buf;
    for (std::size_t r = 0; r < io.size(); ++r) {
      const kinematics::Pose p = world->robot(r).pose();
      CMD_Pos reported{};
      DB_get_from(agent(r), agent(r), CMD_POS, &reported);
      std::snprintf(buf, sizeof buf, ",%.4f,%.4f,%.2f,%.4f,%.4f,%.2f", p.x_m, p.y_m, p.heading_rad * 180 / M_PI,
                    reported.px, reported.py, reported.pa * 180 / M_PI);
      world_log += buf;
    }
    world_log += '\n';
  }

  void record() {
    for (std::size_t r = 0; r < recorders.size(); ++r) {
      while (auto f = recorders[r]->receive()) {
        ++frame_counts[r];
        if (config.record_trace) recorded[r].push_back(*f);
      }
    }
  }
};

VirtualRun::VirtualRun(const VirtualRunConfig& config) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.config = config;
  if (s.config.world.robots.empty()) s.config.world.robots.push_back(physics::Placement{-3.0, 0, -90});
  const std::size_t n = s.config.world.robots.size();
  if (n > 6)
    throw SetupError("a virtual run takes at most 6 robots (agents CAMBADA_1..6); this one has " +
                                std::to_string(n));
  if (!s.config.messages) throw SetupError("no message set");
  if (s.config.interfaces.empty()) {
    for (std::size_t r = 0; r < n; ++r) s.config.interfaces.push_back("vcan" + std::to_string(r));
  }
  if (s.config.agents.empty()) {
    for (std::size_t r = 0; r < n; ++r) s.config.agents.push_back(static_cast<int>(r) + 1);
  }
  if (s.config.interfaces.size() != n || s.config.agents.size() != n) {
    throw SetupError("give one interface and one agent number per robot (" + std::to_string(n) + " robots)");
  }
  for (std::size_t r = 0; r < n; ++r) {
    const int a = s.config.agents[r];
    if (a < 1 || a > 6) throw SetupError("agent numbers are 1..6, got " + std::to_string(a));
    if (std::count(s.config.agents.begin(), s.config.agents.end(), a) > 1) {
      throw SetupError("agent " + std::to_string(a) + " is given to two robots");
    }
  }
  s.world = std::make_unique<physics::World>(s.config.world);
  if (s.config.initial_state) s.world->restore(*s.config.initial_state);  // std::invalid_argument on a mismatch
  s.goals = std::make_unique<GoalWatcher>(s.config.world);
  if (DB_init_all(0) != 0) throw SetupError("cannot attach to the RTDB (see above)");
  s.rtdb = true;
  laptop::AgentConfig agent_cfg;
  agent_cfg.goal_x_m = s.config.world.field.length_m / 2;
  agent_cfg.kick_power = s.config.kick_power;
  s.params.reserve(n);
  s.recorded.resize(n);
  s.frame_counts.resize(n);
  std::vector<vision_emu::Vision> vision;
  for (std::size_t r = 0; r < n; ++r) {
    const int agent = s.config.agents[r];
    // A fresh database for this run: zero every item the agent has.
    for (int item = 0; item < DB_item_count(); ++item) {
      if (DB_item_shared(agent, item) < 0) continue;
      std::vector<unsigned char> zero(static_cast<std::size_t>(DB_item_size(item)), 0);
      DB_put_in(agent, agent, item, zero.data(), 0);
    }
    // The agent asks the handler to put the odometry where the robot stands.
    const kinematics::Pose at = s.world->robot(r).pose();
    CMD_SetPose pose{static_cast<float>(at.x_m), static_cast<float>(at.y_m), static_cast<float>(at.heading_rad), 0, 1};
    DB_put_in(agent, agent, CMD_SETPOSE, &pose, 0);
    s.io.push_back(std::make_unique<PhysicsRobotIo>(s.world->robot(r)));
    s.params.push_back(node_params_for(s.config.world.robot, s.config.ftt));
    s.buses.push_back(std::make_unique<can_nodes::MemoryBus>(s.clock, s.config.interfaces[r]));
    can_nodes::MemoryBus& bus = *s.buses.back();
    s.nodes.push_back(std::make_unique<RobotNodes>(
        s.config.messages, s.params.back(), *s.io.back(),
        [&bus](const std::string& name) { return std::unique_ptr<can_nodes::Bus>(bus.attach(name)); }, Nanos{0}));
    s.handlers.push_back(
        std::make_unique<HandlerParticipant>(bus, s.config.messages, s.config.ftt.elementary_cycle, s.clock, agent));
    s.agents.push_back(std::make_unique<AgentParticipant>(agent, agent_cfg));
    s.recorders.push_back(bus.attach("trace", 1 << 20));
    s.recorders.back()->set_error_mask(frames::kErrorClassMask);  // error frames belong in the trace
    if (!s.config.faults.empty()) {
      std::vector<std::string> names;
      for (can_nodes::Node* node : s.nodes.back()->nodes()) names.push_back(node->name());
      s.injectors.push_back(std::make_unique<can_nodes::FaultInjector>(s.config.faults, s.config.messages, names,
                                                                       s.config.seed + r, s.config.ftt.bit_rate));
      for (can_nodes::Node* node : s.nodes.back()->nodes()) node->set_fault_hook(s.injectors.back().get());
    }
    vision.emplace_back(s.config.vision, s.world->markings());
  }
  s.vision = std::make_unique<vision_emu::VisionRunner>(
      std::move(vision), [this](std::size_t r, const vision_emu::VisionFrame& f, double) {
        vision_emu::write_vision_info(impl_->agent(r), f);
        impl_->agents[r]->frame_ready(impl_->clock.now());
      });
  s.run = std::make_unique<Lockstep>(s.clock, s.world.get());
  for (std::size_t r = 0; r < n; ++r) {
    for (can_nodes::Node* node : s.nodes[r]->nodes()) s.run->add(*node);
    s.run->add(*s.handlers[r]);
    s.run->add(*s.agents[r]);
  }
  if (s.config.world_log_period > Nanos{0}) {
    s.world_log = "time_s,ball_x_m,ball_y_m,ball_z_m";
    for (std::size_t r = 0; r < n; ++r) {
      const std::string p = "robot" + std::to_string(r) + "_";
      s.world_log += "," + p + "x_m," + p + "y_m," + p + "heading_deg," + p + "reported_x_m," + p + "reported_y_m," +
                     p + "reported_heading_deg";
    }
    s.world_log += '\n';
  }
  s.run->on_physics_step([this](Nanos now) {
    for (std::size_t r = 0; r < impl_->injectors.size(); ++r) {
      impl_->world->robot(r).drain(impl_->injectors[r]->battery_drain_until(now));
    }
    impl_->vision->on_step(*impl_->world);
    impl_->record();
    impl_->log_world(now);
    impl_->goals->step(*impl_->world, now);
  });
}

VirtualRun::~VirtualRun() {
  if (impl_ && impl_->rtdb) DB_free_all(0);
}

void VirtualRun::run_for(Nanos duration) {
  impl_->run->run_for(duration);
  impl_->record();
}

Nanos VirtualRun::now() const noexcept { return impl_->clock.now(); }
const physics::World& VirtualRun::world() const noexcept { return *impl_->world; }

std::vector<RobotOutcome> VirtualRun::outcomes() const {
  std::vector<RobotOutcome> out;
  for (std::size_t r = 0; r < impl_->agents.size(); ++r) {
    RobotOutcome o;
    o.pose = impl_->world->robot(r).pose();
    o.kicks = impl_->agents[r]->kicks();
    o.frames = impl_->frame_counts[r];
    o.bad_frames = impl_->nodes[r]->bad_frames();
    o.battery = impl_->world->robot(r).battery();
    o.charge = impl_->world->robot(r).charge();
    out.push_back(o);
  }
  return out;
}

std::string VirtualRun::trace() const {
  struct Line {
    Nanos time;
    std::size_t bus;
    std::size_t order;
  };
  std::vector<Line> lines;
  for (std::size_t r = 0; r < impl_->recorded.size(); ++r) {
    for (std::size_t i = 0; i < impl_->recorded[r].size(); ++i) lines.push_back({impl_->recorded[r][i].time, r, i});
  }
  std::stable_sort(lines.begin(), lines.end(),
                   [](const Line& a, const Line& b) { return a.time != b.time ? a.time < b.time : a.bus < b.bus; });
  std::string out;
  for (const Line& l : lines) {
    out += frames::format_log_line(l.time, impl_->config.interfaces[l.bus], impl_->recorded[l.bus][l.order].frame);
    out += '\n';
  }
  return out;
}

const std::vector<Goal>& VirtualRun::goals() const noexcept { return impl_->goals->goals(); }

const std::string& VirtualRun::world_log() const noexcept { return impl_->world_log; }

std::vector<can_nodes::FaultCount> VirtualRun::fault_counts() const {
  std::vector<can_nodes::FaultCount> sum;
  for (const auto& inj : impl_->injectors) {
    const auto& c = inj->counts();
    if (sum.empty())
      sum = c;
    else {
      for (std::size_t k = 0; k < c.size(); ++k) sum[k] += c[k];
    }
  }
  return sum;
}

}  // namespace canhil::emulator
