// The FTT-CAN analysis (bus_analysis.hpp) against canhil's own FTT master
// (can_nodes::FttMaster, on a schedule built by frames::FttSchedule) and
// slaves that follow frames/ftt_slot.hpp, on the in-memory bus with a
// bit-timed wire (start-of-frame stamps: what the slaves take a TM's stamp to
// be), in virtual time. Random sets, seeded: every synchronous frame ends in
// its window no later than its bound, and in EC 0 (every message due) each
// reaches it exactly with worst-case bits; every sporadic frame, ready at
// random times or all at once, is through within its bound from the window's
// opening and from ready; and the trace passes the bound check.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "canhil/can_nodes/clock.hpp"
#include "canhil/can_nodes/memory_bus.hpp"
#include "canhil/can_nodes/nodes.hpp"
#include "canhil/can_nodes/virtual_time.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/wire.hpp"
#include "canhil/timing/bound_check.hpp"
#include "canhil/timing/bus_analysis.hpp"
#include "support/test_paths.hpp"

namespace canhil::timing {
namespace {

using namespace std::chrono_literals;
using can_nodes::MemoryBus;
using can_nodes::Wire;
using frames::FttKind;

constexpr Nanos kEc = 10ms;

const std::shared_ptr<const frames::MessageSet>& shipped() {
  static const auto set = frames::MessageSet::load(test::shipped_dbc());  // its TM: 0x010, 8 bytes
  return set;
}

frames::CanFrame frame_of(const BusMessage& m, std::mt19937& rng) {
  frames::CanFrame f;
  f.id = m.id;
  f.len = m.dlc;
  for (std::size_t b = 0; b < f.len; ++b) f.data[b] = static_cast<std::uint8_t>(rng());
  return f;
}

// A producer of one synchronous message: in the window of every EC whose TM schedules it.
class SyncSlave final : public can_nodes::Participant {
 public:
  SyncSlave(MemoryBus& bus, const frames::CanFrame& f, int index) : ep_(bus.attach("sync")), frame_(f), index_(index) {
    const can_nodes::Filter tm_only[] = {can_nodes::Filter::exact(0x010)};
    ep_->set_filters(tm_only);
  }
  std::size_t poll() override {
    std::size_t n = 0;
    for (; auto tf = ep_->receive(); ++n) {
      frames::Tm tm;
      if (shipped()->tm.decode(tf->frame, tm).ok()) slot_.on_tm(tm, tf->time, kEc, 1u << index_);
    }
    return n;
  }
  void tick(Nanos now) override {
    if (!slot_.pending(now)) return;
    ep_->send(frame_);
    slot_.done();
  }
  Nanos next_wakeup() const override { return slot_.when(); }
  bool wakeup_is_own() const override { return true; }

 private:
  std::unique_ptr<can_nodes::MemoryEndpoint> ep_;
  frames::CanFrame frame_;
  int index_;
  frames::SyncSlot slot_;
};

// A producer of one sporadic message: ready at `first`, then again a minimum
// gap and a random extra after each sending (0 extra: as often as it may);
// it goes when the next window opens (frames::async_slot).
class AsyncSlave final : public can_nodes::Participant {
 public:
  AsyncSlave(MemoryBus& bus, const frames::CanFrame& f, Nanos gap, Nanos tm_wire, Nanos first, Nanos extra,
             std::uint32_t seed)
      : ep_(bus.attach("async")), frame_(f), gap_(gap), tm_wire_(tm_wire), ready_(first), extra_(extra), rng_(seed) {
    const can_nodes::Filter tm_only[] = {can_nodes::Filter::exact(0x010)};
    ep_->set_filters(tm_only);
  }
  std::size_t poll() override {
    std::size_t n = 0;
    for (; auto tf = ep_->receive(); ++n) {
      frames::Tm tm;
      if (!shipped()->tm.decode(tf->frame, tm).ok() || send_at_ != kNever || tf->time < ready_) continue;
      send_at_ = frames::async_slot(tf->time, tm_wire_, last_slot_, gap_);
    }
    return n;
  }
  void tick(Nanos now) override {
    if (now < send_at_) return;
    ep_->send(frame_);
    sent.push_back({ready_, send_at_});
    last_slot_ = send_at_;
    send_at_ = kNever;
    ready_ =
        last_slot_ + gap_ +
        (extra_ > Nanos{0} ? Nanos{std::uniform_int_distribution<std::int64_t>(0, extra_.count())(rng_)} : Nanos{0});
  }
  Nanos next_wakeup() const override { return send_at_; }
  bool wakeup_is_own() const override { return true; }
  /// Each sending: when it was ready, and the window's opening it went at.
  std::vector<std::pair<Nanos, Nanos>> sent;

 private:
  std::unique_ptr<can_nodes::MemoryEndpoint> ep_;
  frames::CanFrame frame_;
  Nanos gap_, tm_wire_, ready_, extra_;
  std::mt19937 rng_;
  Nanos send_at_ = kNever;
  Nanos last_slot_ = kLongAgo;
};

// Every frame: its stamp (the first bit) and when it arrived (the last).
class Observer final : public can_nodes::Participant {
 public:
  explicit Observer(MemoryBus& bus, const can_nodes::Clock& clock)
      : ep_(bus.attach("observer", 1 << 16)), clock_(clock) {}
  std::size_t poll() override {
    std::size_t n = 0;
    for (; auto tf = ep_->receive(); ++n) seen.push_back({*tf, clock_.now()});
    return n;
  }
  void tick(Nanos) override {}
  Nanos next_wakeup() const override { return kNever; }
  struct Seen {
    frames::TimedFrame frame;
    Nanos arrived;
  };
  std::vector<Seen> seen;

 private:
  std::unique_ptr<can_nodes::MemoryEndpoint> ep_;
  const can_nodes::Clock& clock_;
};

struct RandomFttSet {
  BusSet set;
  AnalysisConfig config;
  BusAnalysis analysis;
};

// 2 to 12 synchronous messages (periods of 1 to 10 ECs), 1 to 6 sporadic
// (gaps of 50 to 200 ms), random lengths and identifiers, at 125 kbit/s to
// 1 Mbit/s; drawn again until the analysis finds it schedulable with every
// sporadic frame through in the window it was queued for (the wire does not
// close the asynchronous window: a frame that did not fit would run into the
// synchronous one, which real FTT-CAN controllers prevent).
RandomFttSet random_ftt_set(std::mt19937& rng) {
  const std::uint32_t rates[] = {125'000, 250'000, 500'000, 1'000'000};
  const int ecs[] = {1, 2, 3, 5, 10};
  const Nanos gaps[] = {50ms, 100ms, 200ms};
  for (;;) {
    RandomFttSet r;
    r.config.what_if = false;
    r.config.ftt.bit_rate = rates[std::uniform_int_distribution<std::size_t>(0, 3)(rng)];
    r.set.ftt = true;
    r.set.messages.push_back({"TM", 0x010, false, 8, FttKind::kTrigger, -1, kEc, {}, {}});
    std::vector<std::uint32_t> ids{0x010};
    auto fresh_id = [&] {
      for (;;) {
        const auto id = std::uniform_int_distribution<std::uint32_t>(0x011, 0x7FF)(rng);
        if (std::find(ids.begin(), ids.end(), id) == ids.end()) {
          ids.push_back(id);
          return id;
        }
      }
    };
    auto dlc = [&] { return static_cast<std::uint8_t>(std::uniform_int_distribution<int>(0, 8)(rng)); };
    const int syncs = std::uniform_int_distribution<int>(2, 12)(rng);
    for (int i = 0; i < syncs; ++i) {
      r.set.messages.push_back({"S" + std::to_string(i),
                                fresh_id(),
                                false,
                                dlc(),
                                FttKind::kSync,
                                i,
                                kEc * ecs[std::uniform_int_distribution<std::size_t>(0, 4)(rng)],
                                {},
                                {}});
    }
    const int asyncs = std::uniform_int_distribution<int>(1, 6)(rng);
    for (int i = 0; i < asyncs; ++i) {
      r.set.messages.push_back({"A" + std::to_string(i),
                                fresh_id(),
                                false,
                                dlc(),
                                FttKind::kAsync,
                                -1,
                                {},
                                gaps[std::uniform_int_distribution<std::size_t>(0, 2)(rng)],
                                {}});
    }
    r.analysis = analyse_bus(r.set, r.config);
    const bool one_window = std::all_of(r.analysis.async.messages.begin(), r.analysis.async.messages.end(),
                                        [](const AsyncBound& b) { return b.windows == 1; });
    if (r.analysis.schedulable() && one_window) return r;
  }
}

struct Worst {
  std::map<std::uint32_t, Nanos> end_in_window;  // synchronous: last bit less the window's start
  std::map<std::uint32_t, Nanos> ec0_end;        // the same in EC 0
  std::map<std::uint32_t, Nanos> from_open;      // sporadic: last bit less the window's opening
  std::map<std::uint32_t, Nanos> from_ready;     // sporadic: last bit less when it was ready
  BoundReport bounds;
};

// Runs `r` for `duration`; sporadic messages first ready at `first` (each,
// by message), then again after their gap and a random extra up to `extra`.
Worst run(const RandomFttSet& r, Wire::Bits bits, const std::vector<Nanos>& first, Nanos extra, std::mt19937& rng,
          Nanos duration) {
  can_nodes::SimulatedClock clock;
  MemoryBus bus(clock);
  bus.set_wire({r.config.ftt.bit_rate, bits, Wire::Stamp::kStartOfFrame});
  can_nodes::VirtualTime runner(clock);
  runner.add(bus.wire_participant());
  std::vector<frames::FttEntry> entries;
  for (const BusMessage& m : r.set.messages) {
    entries.push_back({m.name, m.kind, m.index, m.period,
                       frames::bits_to_time(frames::worst_case_frame_bits(m.dlc), r.config.ftt.bit_rate)});
  }
  const frames::FttSchedule schedule(entries, r.config.ftt);
  auto master_ep = bus.attach("master");
  can_nodes::FttMaster master(*master_ep, shipped(), schedule, Nanos{0});
  runner.add(master);
  const Nanos tm_wire = frames::bits_to_time(frames::worst_case_frame_bits(8), r.config.ftt.bit_rate);
  std::vector<std::unique_ptr<can_nodes::Participant>> slaves;
  std::map<std::uint32_t, AsyncSlave*> async;
  std::size_t a = 0;
  for (const BusMessage& m : r.set.messages) {
    if (m.kind == FttKind::kSync) {
      slaves.push_back(std::make_unique<SyncSlave>(bus, frame_of(m, rng), m.index));
    } else if (m.kind == FttKind::kAsync) {
      auto s = std::make_unique<AsyncSlave>(bus, frame_of(m, rng), m.min_gap, tm_wire, first[a++], extra, rng());
      async[m.id] = s.get();
      slaves.push_back(std::move(s));
    }
    if (m.kind != FttKind::kTrigger) runner.add(*slaves.back());
  }
  Observer observer(bus, clock);
  runner.add(observer);
  runner.run_until(duration);

  Worst w;
  BoundChecker check(r.analysis, shipped(), Nanos{0});
  Nanos tm_start = kNever;
  frames::Tm tm;
  std::map<std::uint32_t, std::size_t> nth;  // sporadic frames seen so far, by id
  for (const Observer::Seen& s : observer.seen) {
    check.add(s.frame);
    const frames::CanFrame& f = s.frame.frame;
    if (f.id == 0x010) {
      EXPECT_TRUE(shipped()->tm.decode(f, tm).ok());
      tm_start = s.frame.time;
      continue;
    }
    if (tm_start == kNever) continue;
    if (const auto it = async.find(f.id); it != async.end()) {
      const auto& [ready, open] = it->second->sent.at(nth[f.id]++);
      EXPECT_EQ(open, tm_start + tm_wire) << "it went when the window opened";
      w.from_open[f.id] = std::max(w.from_open[f.id], s.arrived - open);
      w.from_ready[f.id] = std::max(w.from_ready[f.id], s.arrived - ready);
    } else {
      const Nanos end = s.arrived - frames::sync_window_start(tm, tm_start, kEc);
      w.end_in_window[f.id] = std::max(w.end_in_window[f.id], end);
      if (tm.ec_counter == 0) w.ec0_end[f.id] = end;
    }
  }
  w.bounds = check.finish();
  return w;
}

void expect_inside(const RandomFttSet& r, const Worst& w, int set) {
  for (const SyncBound& b : r.analysis.sync.messages) {
    EXPECT_LE(w.end_in_window.at(b.id), b.worst_offset) << "set " << set << ", " << b.name;
  }
  for (const AsyncBound& b : r.analysis.async.messages) {
    if (!w.from_open.contains(b.id)) continue;
    EXPECT_LE(w.from_open.at(b.id), b.from_window) << "set " << set << ", " << b.name;
    EXPECT_LE(w.from_ready.at(b.id), b.worst_response) << "set " << set << ", " << b.name;
  }
  EXPECT_TRUE(w.bounds.ok()) << "set " << set << "\n" << format_bounds(w.bounds);
}

TEST(FttBoundsOnTheBus, RandomSetsStayInsideTheirBoundsAndEcZeroReachesTheSynchronousOnes) {
  std::mt19937 rng(2002);
  for (int set = 0; set < 25; ++set) {
    const RandomFttSet r = random_ftt_set(rng);
    std::vector<Nanos> first;
    for (std::size_t i = 0; i < r.analysis.async.messages.size(); ++i)
      first.push_back(Nanos{std::uniform_int_distribution<std::int64_t>(0, (50ms).count())(rng)});
    // Worst-case bits: every synchronous frame of EC 0 ends exactly where its
    // bound says (all are due there, in arbitration order), less the last
    // one's 3-bit intermission that the bound counts in its wire time.
    const Worst worst = run(r, Wire::Bits::kWorstCase, first, 30ms, rng, 500ms);
    expect_inside(r, worst, set);
    const Nanos intermission = frames::bits_to_time(3, r.config.ftt.bit_rate);
    for (const SyncBound& b : r.analysis.sync.messages) {
      EXPECT_EQ(worst.ec0_end.at(b.id), b.worst_offset - intermission) << "set " << set << ", " << b.name << " in EC 0";
    }
    expect_inside(r, run(r, Wire::Bits::kExact, first, 30ms, rng, 500ms), set);
  }
}

TEST(FttBoundsOnTheBus, EverySporadicMessageReadyAtOnceGoesInOneWindowInsideItsBound) {
  std::mt19937 rng(2000);
  for (int set = 0; set < 25; ++set) {
    const RandomFttSet r = random_ftt_set(rng);
    // All ready at the same instant, just before a TM, as often as their gaps allow.
    const std::vector<Nanos> first(r.analysis.async.messages.size(), 5 * kEc - 1ns);
    const Worst worst = run(r, Wire::Bits::kWorstCase, first, Nanos{0}, rng, 500ms);
    expect_inside(r, worst, set);
    // The lowest goes last: after every other sporadic frame, all in one
    // window; it ends 3 bits (its intermission) before their wire times' sum.
    Nanos all{0};
    for (const AsyncBound& b : r.analysis.async.messages) all += b.wire;
    EXPECT_EQ(worst.from_open.at(r.analysis.async.messages.back().id),
              all - frames::bits_to_time(3, r.config.ftt.bit_rate))
        << "set " << set;
  }
}

}  // namespace
}  // namespace canhil::timing
