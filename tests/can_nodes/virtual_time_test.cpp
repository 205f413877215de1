// Virtual time: participants woken exactly when they ask, frames delivered in
// the instant they are sent, the periodic step before the participants of its
// instant, and both ends of run_until.
#include "canhil/can_nodes/virtual_time.hpp"

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

TEST(VirtualTime, WakesEachParticipantExactlyWhenAskedAndDeliversInTheSameInstant) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{5}, Nanos{20}}, log, clock);
  Scripted b("b", bus, {Nanos{20}}, log, clock);
  VirtualTime run(clock);
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

TEST(VirtualTime, TheStepComesEveryPeriodBeforeTheParticipantsOfItsInstant) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {10ms, 15ms}, log, clock);
  VirtualTime run(clock);
  run.set_step(10ms, [&](Nanos now) { log.push_back("step " + std::to_string(now.count())); });
  run.add(a);
  run.run_until(30ms - 1ns);  // both sides of a step's boundary
  EXPECT_EQ(log, (std::vector<std::string>{"step 10000000", "a tick 10000000", "a tick 15000000", "step 20000000"}));
  EXPECT_EQ(run.steps(), 2u);
  run.run_until(30ms);
  EXPECT_EQ(run.steps(), 3u);
}

TEST(VirtualTime, AParticipantMayAskToBeWokenAgainAtOnce) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{7}, Nanos{7}, Nanos{7}}, log, clock);
  VirtualTime run(clock);
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

TEST(VirtualTime, ADeliveryRoundPassesByWhoeverHasNothingToRead) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Scripted a("a", bus, {Nanos{5}, Nanos{9}}, log, clock);
  Counted quiet(bus);
  VirtualTime run(clock);
  run.add(a);
  run.add(quiet);
  run.run_until(Nanos{100});
  EXPECT_EQ(quiet.got, 2u) << "both of a's frames";
  EXPECT_EQ(quiet.polls, 2u) << "polled only when a frame waited";
}

// Answers each frame it hears with its id + 1 (up to `last`), in the
// instant; rings its doorbell when `rings`, else is asked every round.
// Counts the questions a runner puts to it.
class Echo final : public Participant {
 public:
  Echo(std::string name, MemoryBus& bus, std::uint32_t last, bool rings, std::vector<std::string>& log)
      : name_(std::move(name)), ep_(bus.attach(name_)), last_(last), rings_(rings), log_(log) {}
  std::size_t poll() override {
    std::size_t n = 0;
    while (auto f = ep_->receive()) {
      ++n;
      log_.push_back(name_ + " got " + std::to_string(f->frame.id) + " at " + std::to_string(f->time.count()));
      if (f->frame.id < last_) ep_->send(frames::make_data_frame(f->frame.id + 1, {}));
    }
    if (n == 0) ++empty_polls;
    return n;
  }
  bool may_have_frames() const override {
    ++asked_frames;
    return ep_->may_have_frames();
  }
  bool set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) override {
    return rings_ && ep_->set_doorbell(bell, index);
  }
  void tick(Nanos) override {}
  Nanos next_wakeup() const override { return kNever; }
  mutable std::size_t asked_frames = 0;
  std::size_t empty_polls = 0;

 private:
  std::string name_;
  std::unique_ptr<MemoryEndpoint> ep_;
  std::uint32_t last_;
  bool rings_;
  std::vector<std::string>& log_;
};

std::vector<std::string> echo_run(bool rings, std::size_t* asked, std::size_t* empty_polls) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  Echo first("first", bus, 40, rings, log);
  Scripted talker("talker", bus, {Nanos{5}, Nanos{9}, Nanos{30}}, log, clock);
  Echo last("last", bus, 40, rings, log);
  VirtualTime run(clock);
  run.add(first);
  run.add(talker);
  run.add(last);
  run.run_until(Nanos{100});
  *asked = first.asked_frames + last.asked_frames;
  *empty_polls = first.empty_polls + last.empty_polls;
  return log;
}

TEST(VirtualTime, RingingParticipantsGetTheSameFramesInTheSameOrderWithoutBeingAsked) {
  std::size_t asked_when_ringing = 0;
  std::size_t asked_when_asking = 0;
  std::size_t empty = 0;
  const auto ringing = echo_run(true, &asked_when_ringing, &empty);
  EXPECT_EQ(empty, 0u) << "polled only when a frame waited";
  const auto asking = echo_run(false, &asked_when_asking, &empty);
  EXPECT_GT(ringing.size(), 20u) << "answers bounce over several rounds of each instant";
  EXPECT_EQ(ringing, asking) << "the doorbell changes who is asked, not what happens";
  EXPECT_EQ(asked_when_ringing, 2u) << "once each, when added";
  EXPECT_GT(asked_when_asking, 20u);
}

// Keeps its wake-up (wakeup_is_own) and counts how often it is read; the
// test moves it from outside as a step or a caller would.
class Kept final : public Participant {
 public:
  std::size_t poll() override { return 0; }
  bool may_have_frames() const override { return false; }
  void tick(Nanos now) override {
    ticks.push_back(now);
    wake = now + period;
  }
  Nanos next_wakeup() const override {
    ++reads;
    return wake;
  }
  bool wakeup_is_own() const override { return true; }
  Nanos wake = kNever;
  Nanos period = kNever;
  std::vector<Nanos> ticks;
  mutable std::size_t reads = 0;
};

TEST(VirtualTime, AKeptWakeUpIsReadAfterItsOwnTicksTheStepAndEachRunNotAtEveryInstant) {
  SimulatedClock clock;
  MemoryBus bus(clock);
  std::vector<std::string> log;
  std::vector<Nanos> busy(200);
  for (std::size_t i = 0; i < busy.size(); ++i) busy[i] = Nanos{static_cast<std::int64_t>(i + 1)};
  Scripted other("other", bus, busy, log, clock);  // an instant every nanosecond
  Kept kept;
  kept.wake = Nanos{50};
  kept.period = Nanos{100};
  VirtualTime run(clock);
  run.set_step(Nanos{120}, [&](Nanos now) { kept.wake = now + Nanos{3}; });  // as a vision frame wakes an agent
  run.add(other);
  run.add(kept);
  run.run_until(Nanos{200});
  EXPECT_EQ(kept.ticks, (std::vector<Nanos>{Nanos{50}, Nanos{123}})) << "the step's move was seen";
  EXPECT_LT(kept.reads, 10u) << "not read at each of the 200 instants";
  kept.wake = Nanos{210};  // moved by the caller between runs
  run.run_until(Nanos{220});
  EXPECT_EQ(kept.ticks.back(), Nanos{210});
}

TEST(WakeTree, FindsTheEarliestAndEveryOneDueInOrderAsAPlainScanWould) {
  // Random wake-ups set and reset over a tree that grows past its first
  // leaves: the earliest and the due ones always as a scan of the list finds them.
  WakeTree tree;
  std::vector<Nanos> plain;
  std::uint64_t x = 12345;
  const auto draw = [&x](std::uint64_t n) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return (x >> 33) % n;
  };
  for (int turn = 0; turn < 4000; ++turn) {
    if (plain.size() < 40 && draw(4) == 0) {
      const Nanos w = draw(5) == 0 ? kNever : Nanos{static_cast<std::int64_t>(draw(1000))};
      tree.push_back(w);
      plain.push_back(w);
    } else if (!plain.empty()) {
      const std::size_t i = draw(plain.size());
      plain[i] = draw(5) == 0 ? kNever : Nanos{static_cast<std::int64_t>(draw(1000))};
      tree.set(i, plain[i]);
    }
    ASSERT_EQ(tree.size(), plain.size());
    const Nanos now{static_cast<std::int64_t>(draw(1000))};
    std::vector<std::size_t> due, want;
    tree.due(now, due);
    Nanos earliest = kNever;
    for (std::size_t i = 0; i < plain.size(); ++i) {
      if (plain[i] <= now) want.push_back(i);
      earliest = std::min(earliest, plain[i]);
      ASSERT_EQ(tree.at_leaf(i), plain[i]);
    }
    ASSERT_EQ(due, want) << "turn " << turn;
    ASSERT_EQ(tree.earliest(), earliest) << "turn " << turn;
  }
  EXPECT_EQ(plain.size(), 40u) << "the tree grew past 8 and 16 and 32 leaves";
}

}  // namespace
}  // namespace canhil::can_nodes
