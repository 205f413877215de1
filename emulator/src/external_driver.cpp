#include "canhil/emulator/external_driver.hpp"

#include <sys/epoll.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "canhil/emulator/laptop_link.hpp"

namespace canhil::emulator {
namespace {

std::string at_time(Nanos t) {
  char out[48];
  std::snprintf(out, sizeof out, "t = %.3f s", to_seconds(t));
  return out;
}

}  // namespace

// The external processes as one participant: due when one of them asked to
// be woken; after every round of frames, the instant is settled with them.
class ExternalDriver::Processes final : public can_nodes::Participant {
 public:
  explicit Processes(ExternalDriver& driver) : d_(driver) {}
  std::size_t poll() override { return d_.settle(); }
  void tick(Nanos now) override {
    d_.conductor_.set_time(now);
    d_.settle();
  }
  Nanos next_wakeup() const override { return d_.conductor_.next_wakeup(); }

 private:
  ExternalDriver& d_;
};

// The buses' driven wires (the user-space bus's broker runs each on this
// run's clock): due at the next event of any, when each due is run to now
// and what it delivers then is in the sockets before the processes settle.
class ExternalDriver::WireClock final : public can_nodes::Participant {
 public:
  explicit WireClock(ExternalDriver& driver) : d_(driver) {}
  std::size_t poll() override { return 0; }
  bool may_have_frames() const override { return false; }
  void tick(Nanos now) override {
    for (const auto& m : d_.media_) {
      if (m->counts().next_event <= now) m->drive(now);
    }
  }
  Nanos next_wakeup() const override {
    Nanos next = kNever;
    for (const auto& m : d_.media_) next = std::min(next, m->counts().next_event);
    return next;
  }

 private:
  ExternalDriver& d_;
};

ExternalDriver::ExternalDriver(Session& session, lockstep::Conductor& conductor, ExternalOptions options)
    : session_(session),
      conductor_(conductor),
      options_(options),
      watch_(session, {options.record_trace, options.check_timing}),
      time_(clock_) {
  if (session_.scenario().mixes_real_boards()) {
    throw SetupError(
        "emulate = [...] leaves nodes to real boards, and a board keeps the wall clock's time, not "
        "canhil's virtual time: run that scenario in real time (without --virtual-time)");
  }
  const std::size_t n = session_.robot_count();
  can_nodes::SocketCanOptions socket_options;
  socket_options.receive_buffer_bytes = options_.receive_buffer_bytes;
  socket_options.clock = &clock_;  // a frame arrives in the instant it is read
  sockets_.resize(n);
  fenced_.assign(n, 0);
  woken_.assign(n, false);
  cycled_.assign(n, false);
  // The observers are read empty at every instant; a frame dropped at one
  // never reaches the fence's count, and canhil says what it waited for.
  can_nodes::SocketCanOptions observer_options = socket_options;
  observer_options.drops_when_empty = false;
  observer_options.skips_empty_reads = true;  // on the user-space bus: its counts say so, no system call
  for (std::size_t r = 0; r < n; ++r) {
    if (fence_.add(session_.rig(r).interface) != r) throw std::logic_error("one fenced interface per robot");
    observers_.push_back(can_nodes::SocketCanBus::open(session_.rig(r).interface, observer_options));
    observers_.back()->set_error_mask(frames::kErrorClassMask);  // error frames belong in the trace
    if (observers_.back()->state() != can_nodes::BusState::kUp) {
      const std::string& iface = session_.rig(r).interface;
      throw SetupError(iface + " is down; bring it up with `ip link set " + iface + " up`");
    }
  }
  // A timed bus (--bit-rate) is the user-space bus's wire on this run's clock,
  // where every robot's bus is on it; elsewhere the buses deliver at once.
  const BusPhysics& physics = session_.options().bus;
  for (std::size_t r = 0; r < n; ++r) {
    const std::string& iface = session_.rig(r).interface;
    const bool seen = std::any_of(media_.begin(), media_.end(), [&](const auto& m) { return m->interface() == iface; });
    if (!seen) media_.push_back(std::make_unique<can_nodes::SocketCanMedium>(iface, socket_options));
  }
  // canhil's own frames are stamped with the run's time by the shim it runs under.
  timed_ = physics.timed() && conductor_.clocks_virtual_here() &&
           std::all_of(media_.begin(), media_.end(), [](const auto& m) {
             return m->kind() == can_nodes::MediumKind::kUserSpace && !m->counts().timed;
           });
  for (std::size_t k = 0; timed_ && k < media_.size(); ++k) {
    can_nodes::Wire wire = physics.wire(session_.scenario().seed + k);
    wire.driven = true;
    timed_ = media_[k]->set_wire(wire);
    if (timed_) driven_.given.push_back(media_[k].get());
    taken0_.push_back(media_[k]->counts().frames);
    delivered0_.push_back(media_[k]->counts().delivered);
  }
  if (!timed_) driven_.undo();
  // canhil waits for frames in flight on these, not on a timer.
  arrivals_ = ::epoll_create1(EPOLL_CLOEXEC);
  if (arrivals_ < 0) throw SetupError("cannot create an epoll instance for the lockstep's waits");
  auto watch_fd = [this](int fd) {
    epoll_event e{};
    e.events = EPOLLIN;
    e.data.fd = fd;
    ::epoll_ctl(arrivals_, EPOLL_CTL_ADD, fd, &e);
  };
  watch_fd(fence_.descriptor());
  for (const auto& o : observers_) watch_fd(o->fd());
  // The nodes' sockets are fed by the observer (one read per frame for them
  // all, in the bus's order); the kernel queues nothing on them.
  can_nodes::SocketCanOptions node_options = socket_options;
  node_options.fed = true;
  session_.build_nodes(
      [this, &node_options](std::size_t r, const std::string&) {
        auto bus = can_nodes::SocketCanMedium(session_.rig(r).interface, node_options).open_socket();
        sockets_[r].push_back(bus.get());
        return std::unique_ptr<can_nodes::Endpoint>(std::move(bus));
      },
      Session::IoMode::kDirect, Nanos{0});
  processes_ = std::make_unique<Processes>(*this);
  for (std::size_t r = 0; r < n; ++r) {
    for (can_nodes::Node* node : session_.rig(r).nodes->nodes()) time_.add(*node);
  }
  if (timed_) {
    wire_clock_ = std::make_unique<WireClock>(*this);
    time_.add(*wire_clock_);  // its deliveries before the processes settle the instant
  }
  time_.add(*processes_);
  // A team's agent is activated through its PMan table; canhil's own waits on
  // canhil's RTDB's frame signal. Both only in settle(), once the processes'
  // clock reads the frame's instant: a frame is written during the step, and
  // an agent woken there could read the previous instant's time.
  session_.for_each_laptop([](LaptopLink& laptop) {
    laptop.signal_frames(true);
    laptop.defer_activation(true);
  });
  session_.on_vision_frame([this](std::size_t r, Nanos) { woken_[r] = true; });
  // On the user-space bus canhil's looks ask the bus's counts in memory
  // whether a frame reached an observer, or the fence, instead of polling.
  if (std::all_of(observers_.begin(), observers_.end(), [](const auto& o) { return o->waiting().has_value(); })) {
    arrived_ = [this] {
      const bool at_an_observer =
          std::any_of(observers_.begin(), observers_.end(), [](const auto& o) { return o->waiting() == true; });
      return at_an_observer || (waiting_on_fence_ && !unfenced()) || (wire_wanted_ > 0 && taken() >= wire_wanted_);
    };
  }
  time_.set_step(session_.step_period(), [this](Nanos now) { session_.step(now); });
}

ExternalDriver::~ExternalDriver() {
  if (arrivals_ >= 0) ::close(arrivals_);
  session_.on_vision_frame(nullptr);
  session_.for_each_laptop([](LaptopLink& laptop) {
    laptop.defer_activation(false);
    laptop.signal_frames(false);
  });
}

void ExternalDriver::activate_agents() {
  session_.for_each_laptop([](LaptopLink& laptop) { laptop.activate(); });
}

void ExternalDriver::run_until(Nanos end) {
  if (!started_) {
    // Nothing goes on the bus before every process is ready for it (its sockets open, waiting).
    started_ = true;
    const std::string stuck = conductor_.wait_quiet({}, "its start, before canhil's first frame", options_.start_limit);
    if (!stuck.empty()) throw ProcessStuck(stuck);
  }
  time_.run_until(end);
}

std::uint64_t ExternalDriver::canhil_sent() const {
  std::uint64_t sent = 0;
  for (const auto& robot : sockets_) {
    for (const can_nodes::SocketCanBus* s : robot) sent += s->frames_sent();
  }
  return sent;
}

void ExternalDriver::observe() {
  for (std::size_t r = 0; r < observers_.size(); ++r) {
    while (auto f = observers_[r]->receive()) {
      ++observed_;
      if (f->frame.kind != frames::FrameKind::kError) ++observed_frames_;
      if (can_nodes::DeliveryFence::counts(f->frame)) ++fenced_[r];
      for (can_nodes::SocketCanBus* s : sockets_[r]) s->feed(f->frame);
      watch_.add(r, {f->frame, clock_.now()});
    }
  }
}

std::string ExternalDriver::in_flight(std::uint64_t sent) {
  waiting_on_fence_ = false;
  wire_wanted_ = 0;
  observe();
  if (timed_) {
    if (taken() < sent) {
      wire_wanted_ = sent;
      return "the frames sent to reach the bus's wire";
    }
    if (observed_frames_ < delivered()) return "the frames the wire delivered to reach the bus";
  } else if (observed_ < sent) {
    return "the frames sent to reach the bus";
  }
  // The observer may have a frame that later sockets have not yet: the fence says when all have it.
  fence_.drain();
  if (const auto r = unfenced()) {
    waiting_on_fence_ = true;
    return "the frames on " + session_.rig(*r).interface + " to reach every socket";
  }
  return {};
}

std::uint64_t ExternalDriver::taken() const {
  std::uint64_t n = 0;
  for (std::size_t k = 0; k < taken0_.size(); ++k) n += media_[k]->counts().frames - taken0_[k];
  return n;
}

std::uint64_t ExternalDriver::delivered() const {
  std::uint64_t n = 0;
  for (std::size_t k = 0; k < delivered0_.size(); ++k) n += media_[k]->counts().delivered - delivered0_[k];
  return n;
}

std::optional<std::size_t> ExternalDriver::unfenced() {
  for (std::size_t r = 0; r < fenced_.size(); ++r) {
    if (!fence_.reached(r, fenced_[r])) return r;
  }
  return std::nullopt;
}

std::size_t ExternalDriver::settle() {
  conductor_.set_time(clock_.now());
  activate_agents();  // the frames of this instant's step: the clock reads its time now
  const std::uint64_t ours = canhil_sent();
  bool woke = false;
  for (const bool w : woken_) woke = woke || w;
  const std::uint64_t sent_now = ours + conductor_.frames_sent();
  if (settled_once_ && !woke && conductor_.epoch() == settled_epoch_ && on_buses(sent_now) == announced_ &&
      (!timed_ || taken() >= sent_now)) {
    // Nothing happened since the processes were last quiet: no frame, no
    // activation, no wake-up due (set_time() nudges then). Most instants.
    return 0;
  }
  bool agents_due = false;  // set once a woken agent has been told to look
  // Each robot's PMan table is its team's.
  auto masters_of = [this](std::size_t r) -> pman::Masters* {
    LaptopLink* laptop = session_.laptop(session_.rig(r).team);
    return laptop != nullptr ? laptop->masters() : nullptr;
  };
  // Until nothing new happens: wait for the processes to be quiet and for every
  // frame sent to have reached every socket; then, if frames are new to the
  // processes or an agent was activated, nudge them to look again.
  // An agent's first activation has the start-up limit.
  bool first_activation = false;
  for (std::size_t r = 0; r < woken_.size(); ++r) first_activation = first_activation || (woken_[r] && !cycled_[r]);
  const std::optional<Nanos> limit = first_activation ? std::optional<Nanos>(options_.start_limit) : std::nullopt;
  for (;;) {
    std::uint64_t sent = 0;
    const std::string stuck = conductor_.wait_quiet(
        [&]() -> std::string {
          sent = ours + conductor_.frames_sent();
          std::string missing = in_flight(sent);
          if (!missing.empty() || !agents_due) return missing;
          for (std::size_t r = 0; r < woken_.size(); ++r) {
            pman::Masters* masters = masters_of(r);
            if (woken_[r] && masters != nullptr && !masters->all_idle(session_.rig(r).agent)) {
              return (session_.rig(r).team == 0 ? "" : "the second team's ") + std::string("agent ") +
                     std::to_string(session_.rig(r).agent) + "'s PMAN_epilogue";
            }
          }
          return {};
        },
        "what canhil did at " + at_time(clock_.now()), limit, arrivals_, arrived_);
    if (!stuck.empty()) {
      observe();  // what reached the bus up to the stop belongs in the trace
      throw ProcessStuck(stuck);
    }
    const std::uint64_t arrived = on_buses(sent);
    if (arrived == announced_ && !woke) break;
    announced_ = arrived;
    agents_due = agents_due || woke;
    // New frames concern only the threads waiting on descriptors; an
    // activation (a semaphore, a signal, a team's own means) every thread.
    conductor_.nudge(woke ? lockstep::kEveryChange : lockstep::kDescriptors);
    woke = false;
  }
  for (std::size_t r = 0; r < woken_.size(); ++r) cycled_[r] = cycled_[r] || woken_[r];
  woken_.assign(woken_.size(), false);
  settled_once_ = true;
  settled_epoch_ = conductor_.epoch();
  from_processes_ = observed_ - ours;
  // Every frame new on the buses, canhil's own too: the nodes read them in
  // the next round, now that the fence says they are in every socket (a
  // node polling before this settle may have looked too early).
  const std::uint64_t fresh = observed_ - observed_at_settle_;
  observed_at_settle_ = observed_;
  return static_cast<std::size_t>(fresh);
}

std::string ExternalDriver::trace() const { return watch_.trace(); }

std::uint64_t ExternalDriver::ftt_violations(std::size_t robot) const { return watch_.ftt_violations(robot); }

std::uint64_t ExternalDriver::trace_hash() const noexcept { return watch_.trace_hash(); }

}  // namespace canhil::emulator
