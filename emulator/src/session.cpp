#include "canhil/emulator/session.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdio>

#include "canhil/base/setup_error.hpp"
#include "canhil/emulator/laptop_link.hpp"
#include "canhil/emulator/physics_robot_io.hpp"
#include "canhil/emulator/referee_desk.hpp"

namespace canhil::emulator {

namespace {

// The node names a fault rule may target, from the one table.
std::vector<std::string> robot_node_names() { return {can_nodes::kNodeNames.begin(), can_nodes::kNodeNames.end()}; }

}  // namespace

// Whoever wants the whole world's state waits here until the stepping thread saves it.
struct Session::StateRequests {
  std::mutex mutex;
  std::condition_variable saved;
  std::atomic<bool> asked{false};
  std::uint64_t generation = 0;
  physics::WorldState state;
};

Session::Session(RunPlan plan)
    : plan_(std::move(plan)),
      scenario_(plan_.scenario),
      options_(plan_.options),
      goals_(scenario_.world),
      state_requests_(std::make_unique<StateRequests>()) {
  coach_ = scenario_.coach;
  world_ = std::make_unique<physics::World>(scenario_.world);
  if (options_.initial_state) {
    try {
      world_->restore(*options_.initial_state);
    } catch (const SetupError& e) {
      throw SetupError(std::string("the saved world does not fit the scenario: ") + e.what());
    }
  }
  step_period_ = from_seconds(scenario_.world.simulation.step_s);
  if (scenario_.referee.enabled.value_or(scenario_.teams.size() > 1))
    referee_ = std::make_unique<RefereeDesk>(scenario_);
  const std::size_t n = scenario_.robot_count();
  for (std::size_t t = 0; t < scenario_.teams.size(); ++t) {
    relocation_delay_.push_back(from_seconds(scenario_.laptop_of(t).relocation_delay_s));
  }
  placements_seen_.assign(n, 0);
  rigs_.resize(n);
  for (std::size_t r = 0; r < n; ++r) {
    Rig& rig = rigs_[r];
    rig.index = r;
    rig.team = scenario_.team_of(r);
    rig.agent = scenario_.agents[r];
    rig.in_team = r - scenario_.teams[rig.team].first_robot;
    rig.interface = scenario_.interfaces[r];
    // Robot r draws from seed + r: robots' faults are independent and repeatable.
    // Every robot has an injector, rules or not, so a fault injected later needs no new hook.
    rig.faults = std::make_unique<can_nodes::FaultInjector>(scenario_.faults, options_.messages, robot_node_names(),
                                                            scenario_.seed + r, options_.ftt.bit_rate);
    rig.faults->leave_errors_to_the_wire(options_.bus.timed() && !options_.realtime);
  }
  for (const can_nodes::FaultRule& rule : scenario_.faults) check_wire_rule(rule);
  if (options_.vision_on) {
    for (std::size_t t = 0; t < scenario_.teams.size(); ++t) {
      const Team& team = scenario_.teams[t];
      const auto first = scenario_.agents.begin() + static_cast<std::ptrdiff_t>(team.first_robot);
      const std::vector<int> agents(first, first + static_cast<std::ptrdiff_t>(team.robots));
      team_coaches_.push_back(team_coach(t));
      laptops_.push_back(
          std::make_unique<LaptopLink>(plan_.laptops.at(t), agents, team_coaches_.back(), static_cast<int>(t)));
    }
    std::vector<vision_emu::Vision> vision;
    const vision_emu::VisionParams& params = options_.vision;  // the scenario's [vision] merged in by the plan
    for (std::size_t r = 0; r < n; ++r) {
      // Robot r's camera draws from the run's seed: another seed, another match.
      vision_emu::VisionParams mine = params;
      mine.seed = static_cast<unsigned>(params.seed + 1000 * scenario_.seed + r);
      vision.emplace_back(mine, world_->markings());
    }
    vision_ = std::make_unique<vision_emu::VisionRunner>(
        std::move(vision), [this](std::size_t r, const vision_emu::VisionFrame& f, double) {
          laptops_[rigs_[r].team]->vision_frame(rigs_[r].in_team, f);
          if (r == vision_watched_.load(std::memory_order_relaxed)) {
            if (!vision_seen_) vision_seen_.emplace();
            vision_seen_->robot = r;
            vision_seen_->time_s = to_seconds(now_);
            vision_seen_->lines = f.lines;
            vision_seen_->obstacles = f.obstacles;
            vision_seen_->balls = f.balls;
          }
          if (frame_hook_) frame_hook_(r, now_);
        });
  }
  if (options_.world_log_period > Nanos{0}) {
    std::vector<WorldLogTeam> teams;
    for (const Team& t : scenario_.teams) teams.push_back({t.name, t.attacks_positive_x});
    std::vector<WorldLogRobot> robots;
    for (const Rig& rig : rigs_) robots.push_back({rig.team, rig.agent, rig.interface});
    world_log_.emplace(options_.world_log_period, teams, robots);
  }
  publish(0);
}

Session::~Session() {
  for (Rig& rig : rigs_) rig.nodes.reset();  // before the I/O they use
}

void Session::build_nodes(const Endpoints& endpoints, IoMode mode, Nanos start) {
  node_params_ = node_params_for(scenario_.world.robot, options_.ftt);
  const FirmwareSettings& fw = scenario_.firmware;
  if (fw.watchdog_ms) node_params_.watchdog = from_ms(*fw.watchdog_ms);
  if (fw.motor_watchdog_ms) node_params_.motor_watchdog = from_ms(*fw.motor_watchdog_ms);
  if (fw.alive_timeout_ms) node_params_.alive_timeout = from_ms(*fw.alive_timeout_ms);
  for (Rig& rig : rigs_) {
    physics::Robot& robot = world_->robot(rig.index);
    if (mode == IoMode::kShared) {
      auto shared = std::make_unique<SharedRobotIo>(robot);
      rig.shared = shared.get();
      rig.io = std::move(shared);
    } else {
      rig.shared = nullptr;
      rig.io = std::make_unique<PhysicsRobotIo>(robot);
    }
    const std::size_t r = rig.index;
    rig.nodes = std::make_unique<can_nodes::RobotNodes>(
        options_.messages, node_params_, *rig.io, [&](const std::string& node) { return endpoints(r, node); }, start,
        scenario_.emulate.at(r));
    rig.faults->start_at(start);  // rule times count from the run's start, not the clock's epoch
    rig.nodes->set_fault_hook(rig.faults.get());
  }
}

void Session::apply_world_changes() {
  if (!any_world_change_.load(std::memory_order_acquire)) return;
  std::vector<Change> changes;
  {
    const std::lock_guard lock(changes_mutex_);
    changes.swap(world_changes_);
    any_world_change_ = false;
  }
  for (const Change& c : changes) apply_now(c);
}

void Session::serve_state_requests() {
  StateRequests& q = *state_requests_;
  if (!q.asked.load(std::memory_order_acquire)) return;
  physics::WorldState state = world_->save();
  const std::lock_guard lock(q.mutex);
  q.state = std::move(state);
  ++q.generation;
  q.asked = false;
  q.saved.notify_all();
}

std::optional<physics::WorldState> Session::saved_state(std::chrono::milliseconds wait) const {
  StateRequests& q = *state_requests_;
  std::unique_lock lock(q.mutex);
  const std::uint64_t before = q.generation;
  q.asked = true;
  if (!q.saved.wait_for(lock, wait, [&] { return q.generation != before; })) return std::nullopt;
  return q.state;
}

void Session::settle() {
  apply_bus_changes();
  apply_world_changes();
  serve_state_requests();
  publish(steps_);
}

void Session::step(Nanos now, bool with_bus_changes) {
  if (with_bus_changes) apply_bus_changes();
  before_step();
  if (options_.time_steps) {
    const std::uint64_t contacts = world_->contact_points();
    const Nanos spent = thread_cpu_of([this] { world_->step(); });
    step_timing_.physics.add(world_->contact_points() - contacts, spent);
  } else {
    world_->step();
  }
  after_step(now);
}

void Session::before_step() {
  apply_world_changes();
  serve_state_requests();
  for (Rig& rig : rigs_) {
    if (rig.shared != nullptr) rig.shared->apply_commands();
  }
}

CoachState Session::team_coach(std::size_t team) const {
  const Team& t = scenario_.teams.at(team);
  CoachState c;
  c.game_state = coach_.state_of(team);
  c.attacks_positive_x = t.attacks_positive_x;
  const auto first = coach_.players.begin() + static_cast<std::ptrdiff_t>(t.first_robot);
  c.players.assign(first, first + static_cast<std::ptrdiff_t>(t.robots));
  return c;
}

void Session::write_coaches() {
  for (std::size_t t = 0; t < laptops_.size(); ++t) {
    team_coaches_[t] = team_coach(t);
    laptops_[t]->write_coach(team_coaches_[t]);
  }
}

void Session::referee_step(Nanos now, std::optional<bool> goal_positive_x) {
  const RefereeDesk::Outcome out = referee_->step(*world_, now, goal_positive_x);
  if (out.call) {
    const Referee& referee = referee_->referee();
    std::vector<std::string> states;
    for (std::size_t t = 0; t < scenario_.teams.size(); ++t) states.push_back(referee.state_for(*out.call, t));
    set_team_states(std::move(states));
    if (world_log_) {
      WorldLogCall logged{to_seconds(out.call->time),
                          std::string(restart_name(out.call->restart)),
                          out.call->team ? scenario_.teams[*out.call->team].name : std::string("-"),
                          out.call->spot.x(),
                          out.call->spot.y(),
                          {}};
      for (const int goals : referee.score()) logged.score.push_back(std::to_string(goals));
      world_log_->call(logged);
    }
    for (std::size_t r = 0; r < placements_seen_.size(); ++r) {
      for (; placements_seen_[r] < referee_->placements(r); ++placements_seen_[r]) relocate_later(r, now);
    }
    if (referee_hook_) referee_hook_(*out.call);
  } else if (out.resume) {
    set_team_states(std::vector<std::string>(scenario_.teams.size(), "start"));
  }
}

void Session::set_team_states(std::vector<std::string> states) {
  CoachState next = coach_;
  next.team_game_states = std::move(states);
  if (next == coach_) return;
  coach_ = std::move(next);
  write_coaches();
  if (coach_hook_) coach_hook_(coach_);
}

void Session::after_step(Nanos now) {
  ++steps_;
  now_ = now;
  for (Rig& rig : rigs_) {
    if (rig.shared != nullptr) rig.shared->publish();
    world_->robot(rig.index).drain(rig.faults->battery_drain_until(now));
  }
  if (vision_) {
    const auto see = [this] { vision_->on_step(*world_); };
    if (options_.time_steps) {
      step_timing_.vision += thread_cpu_of(see);
    } else {
      see();
    }
  }
  for (std::size_t t = 0; t < laptops_.size(); ++t) laptops_[t]->step(now, team_coaches_[t]);
  log_world(now);
  // A ball into a goal before the referee's restart is taken scores nothing (the referee retakes it).
  const Eigen::Vector2d ball = world_->ball_position().head<2>();
  const std::optional<bool> entered = goals_.step(*world_, now, !referee_ || referee_->referee().ball_in_play_at(ball));
  if (referee_) referee_step(now, entered);
  for (const std::size_t r : moved_) relocate_later(r, now);
  moved_.clear();
  if (!relocations_due_.empty()) count_relocations(now);
  if (step_hook_) step_hook_(now);
  publish(steps_);
}

void Session::relocate_later(std::size_t robot, Nanos now) {
  relocations_due_.emplace_back(now + relocation_delay_[rigs_[robot].team], robot);
}

void Session::mark_moved(std::size_t robot) {
  if (std::find(moved_.begin(), moved_.end(), robot) == moved_.end()) moved_.push_back(robot);
}

// The relocations due by now into the coach's orders, written at once (a
// team's agent relocalises when the count changes; it must not wait for the
// next coach period).
void Session::count_relocations(Nanos now) {
  const auto due = [now](const std::pair<Nanos, std::size_t>& d) { return d.first <= now; };
  bool counted = false;
  for (const auto& [when, robot] : relocations_due_) {
    if (when > now) continue;
    ++coach_.players.at(robot).relocations;
    counted = true;
  }
  std::erase_if(relocations_due_, due);
  if (!counted) return;
  write_coaches();
  if (coach_hook_) coach_hook_(coach_);
}

void Session::apply_bus_changes() {
  if (!any_bus_change_.load(std::memory_order_acquire)) return;
  std::vector<Change> changes;
  {
    const std::lock_guard lock(changes_mutex_);
    changes.swap(bus_changes_);
    any_bus_change_ = false;
  }
  for (const Change& c : changes) apply_now(c);
}

void Session::apply(Change change) {
  // Checked here, where the caller hears of a mistake; applied on the right thread.
  if (const auto* m = std::get_if<MoveRobot>(&change); m != nullptr && m->robot >= rigs_.size()) {
    throw SetupError("no robot " + std::to_string(m->robot) + "; the run has " + std::to_string(rigs_.size()));
  }
  if (const auto* m = std::get_if<MoveObstacle>(&change); m != nullptr && m->obstacle >= world_->obstacle_count()) {
    throw SetupError("no obstacle " + std::to_string(m->obstacle) + "; the run has " +
                     std::to_string(world_->obstacle_count()));
  }
  if (const auto* c = std::get_if<SetCoach>(&change)) {
    if (c->game_state && !is_game_state(*c->game_state)) {
      std::string list;
      for (const auto g : kGameStates) list += (list.empty() ? "" : ", ") + std::string(g);
      throw SetupError("\"" + *c->game_state + "\" is not a game state; use one of " + list);
    }
    if ((c->running || c->role) && !c->robot) throw SetupError("say which robot the coach's order is for");
    if (c->robot && *c->robot >= rigs_.size()) {
      throw SetupError("no robot " + std::to_string(*c->robot) + "; the run has " + std::to_string(rigs_.size()));
    }
    if (c->role && c->role->empty()) throw SetupError("a role needs a name, e.g. \"striker\"");
    if (c->team && *c->team >= scenario_.teams.size()) {
      throw SetupError("no team " + std::to_string(*c->team) + "; the run has " +
                       std::to_string(scenario_.teams.size()));
    }
    if (c->team && !c->game_state) throw SetupError("a team's order is its game state: give game_state");
  }
  if (const auto* w = std::get_if<RestoreWorld>(&change)) {
    if (w->state.robots.size() != rigs_.size() || w->state.obstacles.size() != world_->obstacle_count()) {
      throw SetupError("the saved world has " + std::to_string(w->state.robots.size()) + " robot(s) and " +
                       std::to_string(w->state.obstacles.size()) + " obstacle(s); this run has " +
                       std::to_string(rigs_.size()) + " and " + std::to_string(world_->obstacle_count()));
    }
  }
  const bool bus = std::holds_alternative<InjectFault>(change);
  if (bus) {
    const can_nodes::FaultRule& rule = std::get<InjectFault>(change).rule;
    if (rule.kind == can_nodes::FaultKind::kErrorFrame) {
      std::string refused;
      {
        const std::lock_guard lock(changes_mutex_);
        refused = error_frames_refused_;
      }
      if (!refused.empty()) throw SetupError("fault '" + rule.text + "': " + refused);
    }
    // The target must exist: the same check the injector makes at start.
    can_nodes::FaultInjector check({rule}, options_.messages, robot_node_names(), 0);
    check_wire_rule(rule);
  }
  const std::lock_guard lock(changes_mutex_);
  if (bus_changes_.size() + world_changes_.size() >= kMaxPendingChanges) {
    throw SetupError("too many changes are waiting for the next step; send fewer, or wait for the run to step");
  }
  if (bus) {
    bus_changes_.push_back(std::move(change));
    any_bus_change_ = true;
  } else {
    world_changes_.push_back(std::move(change));
    any_world_change_ = true;
  }
}

void Session::check_wire_rule(const can_nodes::FaultRule& rule) const {
  if (!can_nodes::wire_only(rule.kind)) return;
  if (!options_.bus.timed()) {
    throw SetupError("fault '" + rule.text +
                     "': acts on the wire, and this run's bus is instant: give it a bit rate ([bus] bit_rate in the "
                     "scenario, or --bit-rate)");
  }
  if (options_.realtime || options_.external) {
    throw SetupError("fault '" + rule.text +
                     "': acts on canhil's timed wire, which runs in virtual time (canhil run --virtual-time); a run "
                     "on SocketCAN interfaces has the kernel's or the user-space bus's own");
  }
}

void Session::refuse_error_frames(std::string why) {
  const std::lock_guard lock(changes_mutex_);
  error_frames_refused_ = std::move(why);
}

void Session::apply_now(const Change& change) {
  if (const auto* m = std::get_if<MoveRobot>(&change)) {
    world_->robot(m->robot).place(m->to);
    mark_moved(m->robot);
  } else if (const auto* b = std::get_if<MoveBall>(&change)) {
    world_->place_ball(b->position, b->velocity);
  } else if (const auto* o = std::get_if<MoveObstacle>(&change)) {
    world_->place_obstacle(o->obstacle, o->x_m, o->y_m);
  } else if (const auto* f = std::get_if<InjectFault>(&change)) {
    for (Rig& rig : rigs_) rig.faults->add_rule(f->rule);
    const bool on_wire = can_nodes::wire_only(f->rule.kind) || (f->rule.kind == can_nodes::FaultKind::kErrorFrame &&
                                                                options_.bus.timed() && !options_.realtime);
    if (on_wire && wire_fault_hook_) wire_fault_hook_(f->rule);
  } else if (const auto* w = std::get_if<RestoreWorld>(&change)) {
    // The world's clock goes on: the saved bodies come back, not the saved time.
    physics::WorldState state = w->state;
    const double shift = world_->time_s() - state.time_s;
    state.time_s += shift;
    for (physics::RobotState& r : state.robots) {
      if (r.last_kick_time_s >= 0) r.last_kick_time_s += shift;
    }
    world_->restore(state);
    for (std::size_t r = 0; r < rigs_.size(); ++r) mark_moved(r);  // every robot put where it was saved
  } else if (const auto* c = std::get_if<SetCoach>(&change)) {
    CoachState next = coach_;
    if (c->game_state && c->team) {
      if (next.team_game_states.empty()) next.team_game_states.assign(scenario_.teams.size(), next.game_state);
      next.team_game_states.at(*c->team) = *c->game_state;
    } else if (c->game_state) {
      next.game_state = *c->game_state;
      next.team_game_states.clear();
    }
    if (c->robot) {
      CoachPlayer& p = next.players.at(*c->robot);
      if (c->running) p.running = *c->running;
      if (c->role) p.role = *c->role;
    }
    if (next != coach_) {
      coach_ = std::move(next);
      write_coaches();
      if (coach_hook_) coach_hook_(coach_);
    }
  }
}

void Session::publish(std::uint64_t step) {
  const std::lock_guard lock(snapshot_mutex_);
  WorldSnapshot& s = snapshot_;
  s.time_s = world_->time_s();
  s.steps = step;
  s.ball = world_->ball_position();
  s.ball_velocity = world_->ball_velocity();
  s.robots.resize(world_->robot_count());
  for (std::size_t r = 0; r < s.robots.size(); ++r) s.robots[r] = world_->robot(r).pose();
  s.obstacles.resize(world_->obstacle_count());
  for (std::size_t o = 0; o < s.obstacles.size(); ++o) s.obstacles[o] = world_->obstacle_position(o);
  if (s.goals.size() != goals_.goals().size()) s.goals = goals_.goals();
  if (s.coach != coach_) s.coach = coach_;
  if (detail_asked_.exchange(false, std::memory_order_acq_rel)) {
    s.detail.resize(rigs_.size());
    for (const Rig& rig : rigs_) {
      RobotDetail& d = s.detail[rig.index];
      d.achieved = world_->robot(rig.index).twist();
      d.odometry = !laptops_.empty() ? laptops_[rig.team]->reported_pose(rig.in_team) : std::nullopt;
      // The base node's state belongs to the nodes' thread: read only when that is this one.
      d.commanded = rig.shared == nullptr && rig.nodes && rig.nodes->emulates(can_nodes::NodeId::kPicBase)
                        ? rig.nodes->pic_base().commanded()
                        : std::nullopt;
    }
    if (vision_watched_.load(std::memory_order_relaxed) == kNoRobot) {
      s.vision.reset();
    } else {
      s.vision = vision_seen_;
    }
    if (detail_hook_) detail_hook_(s);
  }
}

WorldSnapshot Session::snapshot() const {
  const std::lock_guard lock(snapshot_mutex_);
  return snapshot_;
}

WorldSnapshot Session::detailed_snapshot() const {
  detail_asked_.store(true, std::memory_order_release);
  return snapshot();
}

void Session::watch_vision(std::optional<std::size_t> robot) {
  if (robot && *robot >= rigs_.size()) {
    throw SetupError("no robot " + std::to_string(*robot) + "; the run has " + std::to_string(rigs_.size()));
  }
  if (robot && !vision_) throw SetupError("this run has no vision (canhil nodes)");
  vision_watched_.store(robot.value_or(kNoRobot), std::memory_order_relaxed);
}

std::vector<can_nodes::FaultCount> Session::fault_counts() const {
  std::vector<can_nodes::FaultCount> sum;
  for (const Rig& rig : rigs_) {
    const auto c = rig.faults->counts();
    if (sum.empty()) {
      sum = c;
    } else {
      for (std::size_t k = 0; k < c.size() && k < sum.size(); ++k) sum[k] += c[k];
    }
  }
  return sum;
}

void Session::log_world(Nanos now) {
  if (!world_log_ || !world_log_->due(now)) return;
  world_log_->begin_row(now, world_->ball_position());
  for (const Rig& rig : rigs_) {
    // The pose as stored (a float in canhil's layout), so the log reads as before.
    const kinematics::Pose reported = !laptops_.empty()
                                          ? laptops_[rig.team]->reported_pose(rig.in_team).value_or(kinematics::Pose{})
                                          : kinematics::Pose{};
    world_log_->robot(world_->robot(rig.index).pose(), reported);
  }
  world_log_->end_row();
}

}  // namespace canhil::emulator
