// Virtual time: participants woken exactly when they ask, frames delivered in
// the instant they are sent, the periodic step before the participants of its
// instant, and both ends of run_until.
#include "canhil/can_nodes/lockstep.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "canhil/can_nodes/memory_bus.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

// Wakes at the times it is given; at each wake-up it sends a frame and notes
// what happened into a shared log, as do the frames it receives.
class Scripted final : public Participant {
 public:
  Scripted(std::string name, MemoryBus& bus, std::vector<Nanos> wakes, std::vector<std::string>& log,
           const Clock& clock)
      : name_(std::move(name)), ep_(bus.attach(name_)), wakes_(std::move(wakes)), log_(log), clock_(clock) {}
  std::size_t poll() override {
    std::size_t n = 0;
    while (auto f = ep_->receive()) {
      ++n;
      log_.push_back(name_ + " got " + std::to_string(f->frame.id) + " at " + std::to_string(f->time.count()));
    }
    return n;
  }
  void tick(Nanos now) override {
    log_.push_back(name_ + " tick " + std::to_string(now.count()));
    wakes_.erase(wakes_.begin());
    ep_->send(frames::make_data_frame(static_cast<std::uint32_t>(now.count() % 0x7FF), {}));
    EXPECT_EQ(clock_.now(), now);
  }
  Nanos next_wakeup() const override { return wakes_.empty() ? kNever : wakes_.front(); }

 private:
  std::string name_;
  std::unique_ptr<MemoryEndpoint> ep_;
  std::vector<Nanos> wakes_;
  std::vector<std::string>& log_;
  const Clock& clock_;
};

TEST(Lockstep, WakesEachParticipantExactlyWhenAskedAndDeliversInTheSameInstant) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{5}, Nanos{20}}, log, clock);
  Scripted b("b", bus, {Nanos{20}}, log, clock);
  Lockstep run(clock);
  run.add(a);
  run.add(b);
  run.run_until(Nanos{19});
  EXPECT_EQ(log, (std::vector<std::string>{"a tick 5", "b got 5 at 5"}));
  EXPECT_EQ(clock.now(), Nanos{19}) << "time ends where asked, even with nothing due";
  run.run_until(Nanos{20});  // inclusive: what is due at 20 happens
  EXPECT_EQ(log, (std::vector<std::string>{"a tick 5", "b got 5 at 5", "a tick 20", "b tick 20", "a got 20 at 20",
                                           "b got 20 at 20"}))
      << "ticked in the order added, then delivered";
}

TEST(Lockstep, TheStepComesEveryPeriodBeforeTheParticipantsOfItsInstant) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {10ms, 15ms}, log, clock);
  Lockstep run(clock);
  run.set_step(10ms, [&](Nanos now) { log.push_back("step " + std::to_string(now.count())); });
  run.add(a);
  run.run_until(30ms - 1ns);  // both sides of a step's boundary
  EXPECT_EQ(log, (std::vector<std::string>{"step 10000000", "a tick 10000000", "a tick 15000000", "step 20000000"}));
  EXPECT_EQ(run.steps(), 2u);
  run.run_until(30ms);
  EXPECT_EQ(run.steps(), 3u);
}

TEST(Lockstep, AParticipantMayAskToBeWokenAgainAtOnce) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{7}, Nanos{7}, Nanos{7}}, log, clock);
  Lockstep run(clock);
  run.add(a);
  run.run_until(Nanos{100});
  EXPECT_EQ(log, (std::vector<std::string>{"a tick 7", "a tick 7", "a tick 7"}));
}

// Counts its polls; says it has frames only when its endpoint has some.
class Counted final : public Participant {
 public:
  explicit Counted(MemoryBus& bus) : ep_(bus.attach("counted")) {}
  std::size_t poll() override {
    ++polls;
    std::size_t n = 0;
    while (ep_->receive()) ++n;
    got += n;
    return n;
  }
  bool may_have_frames() const override { return ep_->may_have_frames(); }
  void tick(Nanos) override {}
  Nanos next_wakeup() const override { return kNever; }
  std::size_t polls = 0;
  std::size_t got = 0;

 private:
  std::unique_ptr<MemoryEndpoint> ep_;
};

TEST(Lockstep, ADeliveryRoundPassesByWhoeverHasNothingToRead) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{5}, Nanos{9}}, log, clock);
  Counted quiet(bus);
  Lockstep run(clock);
  run.add(a);
  run.add(quiet);
  run.run_until(Nanos{100});
  EXPECT_EQ(quiet.got, 2u) << "both of a's frames";
  EXPECT_EQ(quiet.polls, 2u) << "polled only when a frame waited";
}

}  // namespace
}  // namespace canhil::can_nodes
