// canhil/can_nodes/virtual_time.hpp — virtual time: nodes and any other
// participants (a handler, a test playing the laptop) advanced together on a
// simulated clock, as fast as the CPU allows, deterministically; optionally a
// periodic step (the physics world's) on the same clock.
//
// At each instant, in this order: the periodic step (if one ends now), then
// the participants whose wake-up has come, in the order they were added; then
// frames are delivered round after round until no participant has any left
// (frames sent at an instant are received at that instant). Time then jumps
// to the next wake-up or step.
//
// What it costs does not grow with the participants that have nothing to do:
// a participant whose frames arrive in memory rings a Doorbell, and a round
// polls only those rung; one whose wake-up changes only in its own calls has
// it kept, not asked for at every instant, in a tree (WakeTree) that finds
// those due without looking at the others.
//
// Not thread-safe: one thread runs it.
#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include "canhil/base/periodic.hpp"
#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/doorbell.hpp"
#include "canhil/can_nodes/node.hpp"

namespace canhil::can_nodes {

/// Anything a runner drives: nodes, test endpoints, a handler, an agent.
class Participant {
 public:
  virtual ~Participant() = default;
  /// Handles waiting frames; returns how many.
  virtual std::size_t poll() = 0;
  /// Handles at most `budget` waiting frames (real time: a flooded socket must
  /// not hold up deadlines); the rest stay queued. Returns how many.
  virtual std::size_t poll_some(std::size_t budget) {
    (void)budget;
    return poll();
  }
  virtual void tick(Nanos now) = 0;
  virtual Nanos next_wakeup() const = 0;
  /// False only when poll() would certainly handle nothing: a delivery round
  /// then passes this participant by.
  virtual bool may_have_frames() const { return true; }
  /// Asks to have `bell` rung with `index` whenever a frame arrives for this
  /// participant, on everything poll() reads; nullptr stops it. True when it
  /// will (a delivery round then polls it only once rung); false, the
  /// default, when it cannot (then may_have_frames() is asked every round).
  virtual bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) {
    (void)bell;
    (void)index;
    return false;
  }
  /// True when next_wakeup() changes only inside this participant's own
  /// poll(), poll_some() and tick(), or in a runner's periodic step, or, for
  /// one that rings its doorbell, where it rings it: a runner then reads it
  /// after those (after polling it) instead of at every instant. False, the
  /// default, for one moved from outside (by another thread, a process).
  virtual bool wakeup_is_own() const { return false; }
};

/// A node as a participant.
class NodeParticipant final : public Participant {
 public:
  explicit NodeParticipant(Node& node) : node_(node) {}
  std::size_t poll() override { return node_.poll(); }
  std::size_t poll_some(std::size_t budget) override { return node_.poll(budget); }
  void tick(Nanos now) override { node_.tick(now); }
  Nanos next_wakeup() const override { return node_.next_wakeup(); }
  bool may_have_frames() const override { return node_.may_have_frames(); }
  bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) override {
    return node_.set_doorbell(bell, index);
  }
  /// A node moves its wake-ups only in its own tick() and frame handling.
  bool wakeup_is_own() const override { return true; }

 private:
  Node& node_;
};

/// Wake-ups by index, in groups of eight with each group's earliest beside
/// them, and the earliest of all: a change rereads its group (one cache
/// line) and, only when that group's earliest moves later, the groups'
/// earliests, once, when the earliest is next asked for;
/// those due at an instant are found by looking into the groups due. A
/// runner's instant has one or two participants due among dozens (a timed
/// wire's frame end: only its bus), and each instant's looks stay in a few
/// cache lines (a walk down a binary tree touched one per level, each cold
/// after a physics step).
class WakeTree {
 public:
  std::size_t size() const noexcept { return size_; }
  /// One more, at index size(), at `w`.
  void push_back(Nanos w);
  Nanos at_leaf(std::size_t i) const noexcept { return Nanos{leaf_[i]}; }
  void set(std::size_t i, Nanos w) noexcept;
  Nanos earliest() const noexcept {
    if (stale_) refresh_earliest();
    return Nanos{earliest_};
  }
  /// Appends the indices whose wake-up is at or before `now`, in order.
  void due(Nanos now, std::vector<std::size_t>& out) const;
  /// Calls `f(index)` for each index whose wake-up is at or before `now`,
  /// in order; `f` may set() the index it is given (only that one). True
  /// when there was any.
  template <class F>
  bool each_due(Nanos now, F&& f) const {
    const std::int64_t t = now.count();
    if (earliest().count() > t) return false;
    bool any = false;
    for (std::size_t g = 0; g < group_.size(); ++g) {
      if (group_[g] > t) continue;
      for (std::size_t i = g * kGroup; i < (g + 1) * kGroup; ++i) {
        if (leaf_[i] > t) continue;
        f(i);
        any = true;
      }
    }
    return any;
  }

 private:
  static constexpr std::size_t kGroup = 8;
  std::vector<std::int64_t> leaf_;  // index i; kNever in a last group's room
  void refresh_earliest() const noexcept;

  std::vector<std::int64_t> group_;  // each group's earliest
  // The earliest of all, or, while stale_, no later than it: several
  // changes an instant read the groups once, when it is asked for.
  mutable std::int64_t earliest_ = kNever.count();
  mutable bool stale_ = false;
  std::size_t size_ = 0;
};

/// A runner's participants, in the order added (the order they are ticked).
class Participants {
 public:
  Participants() = default;
  Participants(const Participants&) = delete;
  Participants& operator=(const Participants&) = delete;

  void add(Participant& p);
  void add(Node& node);
  /// Delivers frames round after round until nobody has any left (frames sent
  /// while handling frames arrive in the same instant).
  void deliver();
  /// One round, each participant handling at most `budget` frames.
  void deliver_some(std::size_t budget);
  /// Ticks everyone due at now(), delivers, and repeats while anyone is due
  /// (a participant may ask to be woken again at once). now() is re-read each
  /// round. With a `budget`, each delivery is one deliver_some(budget).
  void tick_due(const Clock& clock, std::size_t budget = kUnlimited);
  static constexpr std::size_t kUnlimited = ~std::size_t{0};
  Nanos next_wakeup() const;
  /// Reads every kept wake-up again (after a change from outside the
  /// participants' own calls: a periodic step, a pass's queued changes).
  void refresh();

 private:
  void keep(std::size_t i) {
    if (kept_[i] == 0) return;
    const Nanos w = list_[i]->next_wakeup();
    if (w != wake_.at_leaf(i)) wake_.set(i, w);
  }
  std::size_t poll(std::size_t i);

  std::vector<Participant*> list_;
  std::deque<NodeParticipant> owned_;  // never moved
  WakeTree wake_;                      // kept wake-ups (kNever for those asked)
  std::vector<std::size_t> due_;       // a round's kept participants due, in order
  std::vector<std::uint8_t> kept_;     // wakeup_is_own()
  std::vector<std::uint8_t> rings_;    // set_doorbell() accepted
  std::vector<std::size_t> asked_;     // indices whose wake-up is asked for each time
  std::shared_ptr<Doorbell> bell_ =
      std::make_shared<Doorbell>();  // rung: may have frames (those that cannot ring stay rung)
};

/// The virtual-time runner (the wall-clock one is Realtime, realtime.hpp). Not
/// lockstep::Conductor, which keeps other processes in step with this clock.
class VirtualTime {
 public:
  /// `clock` must outlive the runner; it starts at the clock's time.
  explicit VirtualTime(SimulatedClock& clock) : clock_(clock) {}
  /// A step every `period` from the clock's time on (the first at now +
  /// period), before the participants due at the same instant.
  void set_step(Nanos period, std::function<void(Nanos now)> step);
  /// Participants are ticked in the order added; they must outlive the runner.
  void add(Participant& p) { participants_.add(p); }
  void add(Node& node) { participants_.add(node); }
  /// Runs until the clock reads `end` (inclusive of everything due at `end`).
  void run_until(Nanos end);
  void run_for(Nanos duration) { run_until(clock_.now() + duration); }
  std::uint64_t steps() const noexcept { return steps_; }

 private:
  SimulatedClock& clock_;
  Periodic steps_at_;  ///< the step's instants (none due before set_step)
  std::uint64_t steps_ = 0;
  std::function<void(Nanos)> step_;
  Participants participants_;
};

}  // namespace canhil::can_nodes
