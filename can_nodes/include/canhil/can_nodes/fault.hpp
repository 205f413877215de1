// canhil/can_nodes/fault.hpp — seeded, reproducible fault injection on the
// frames the emulated nodes send.
//
// A fault is one rule, written as text on the command line or in a scenario:
//
//   drop:TARGET[:PROBABILITY]              the frame is not sent
//   delay:TARGET:MILLISECONDS[:PROBABILITY] sent that much later
//   corrupt:TARGET:BYTE[:PROBABILITY]      that data byte is inverted
//   duplicate:TARGET[:COPIES[:PROBABILITY]] extra copies right after
//   silence:TARGET:FROM_SECONDS            nothing from then on
//   error:TARGET[:PROBABILITY]             an error frame destroys the frame; the
//                                          sender's controller sends it again
//   battery:RAIL:PERCENT_PER_SECOND        the pack drains that much faster
//
// and, on a timed wire only (docs/wire.md: wire::FaultRule does them):
//
//   ber:*:RATE                             every bit on the wire flips with this probability
//   noack:TARGET                           its frames go unacknowledged (ACK errors)
//   stuck:NODE                             the node holds the bus dominant
//   babble:NODE[:ID]                       the node sends ID (default 0x000) back to back
//   cut:NODE                               the node is off the bus (a cut cable)
//   busoff:NODE                            the node's controller goes bus-off
//
// TARGET is a message name of the message set (M3_1, M1, TM), a node name
// (Motor1, Pic_base, "FTT master" written FTT_master) or * for every frame;
// for battery, a pack: logic, power12, power24 or * for all three; a wire
// rule's node may also be `laptop`, the controller of the team's handler.
// Any rule may end in @SECONDS to start then, e.g. drop:M4_1:0.5@2, and a
// wire rule in @SECONDS+SECONDS to hold that long, e.g. cut:Motor1@2+0.5. The
// injector draws from its own generator (SplitMix64) seeded by the run's seed,
// so the same rules and seed give the same faults on every machine.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/base/pi_mutex.hpp"
#include "canhil/base/setup_error.hpp"
#include "canhil/can_nodes/node.hpp"

namespace canhil::can_nodes {

enum class FaultKind {
  kDrop,
  kDelay,
  kCorrupt,
  kDuplicate,
  kSilence,
  kErrorFrame,
  kBattery,
  // On a timed wire only:
  kBitErrors,
  kNoAck,
  kStuckDominant,
  kBabbling,
  kCut,
  kBusOff,
};
/// Whether a kind acts on the wire alone (needs a timed bus).
constexpr bool wire_only(FaultKind kind) noexcept { return kind >= FaultKind::kBitErrors; }
/// The node name of the team's handler's controller in wire rules.
inline constexpr const char* kLaptopTarget = "laptop";

struct FaultRule {
  FaultKind kind = FaultKind::kDrop;
  std::string target = "*";
  double probability = 1.0;
  Nanos delay{0};               ///< kDelay
  int byte = 0;                 ///< kCorrupt: 0..7
  int copies = 1;               ///< kDuplicate
  double drain_per_s = 0;       ///< kBattery: fraction of a full pack per second
  double bit_error_rate = 0;    ///< kBitErrors: per bit
  std::uint32_t babble_id = 0;  ///< kBabbling: the frame's 11-bit id
  Nanos from{0};                ///< the rule applies from this time on
  Nanos until = kNever;         ///< and until then (@FROM+SECONDS)
  std::string text;             ///< as written
};

/// Parses one rule; throws SetupError saying what is wrong and the syntax.
FaultRule parse_fault(std::string_view text);

/// What one rule did over a run.
struct FaultCount {
  std::string rule;
  FaultKind kind = FaultKind::kDrop;
  std::uint64_t matched = 0;  ///< frames of its target sent while it was active
  std::uint64_t applied = 0;  ///< frames it changed
  Nanos active{0};            ///< kBattery: how long it drained
  bool on_wire = false;       ///< the timed wire carries it (an `error` rule there): its counts are the controllers'

  /// Adds another robot's count of the same rule.
  FaultCount& operator+=(const FaultCount& other);
};

/// "matched N frames, applied to M" or, for a battery rule, "drained for S s".
std::string describe(const FaultCount& count);

/// The battery packs, in the order of physics::RobotState::charge.
inline constexpr const char* kBatteryPacks[3] = {"logic", "power12", "power24"};

class FaultInjector final : public FaultHook {
 public:
  /// Throws SetupError when a target is neither a message nor a node
  /// name (nor a pack, for battery rules). `bit_rate` times an error frame and
  /// the retransmission it causes.
  FaultInjector(const std::vector<FaultRule>& rules, std::shared_ptr<const frames::MessageSet> set,
                const std::vector<std::string>& node_names, std::uint64_t seed, std::uint32_t bit_rate = 1'000'000);

  /// The time on the nodes' clock the run starts at: rule times (@SECONDS,
  /// silence's FROM_SECONDS) count from here. 0 in virtual time; the wall
  /// clock's start of the run in real time.
  void start_at(Nanos start) noexcept {
    start_ = start;
    drained_until_ = start;
  }

  /// One more rule from now on (a fault injected while the run goes on).
  /// Throws SetupError when its target is neither a message nor a node.
  void add_rule(const FaultRule& rule);

  FaultDecision on_send(const std::string& node, const frames::CanFrame& frame, Nanos now) override;
  /// On a timed wire the wire does `error` rules too (wire_faults.hpp): on_send leaves them.
  void leave_errors_to_the_wire(bool on) noexcept { errors_on_wire_ = on; }
  /// The fraction of each full pack (logic, power12, power24) the battery rules
  /// take between the previous call and `now`, for the physics to remove.
  std::array<double, 3> battery_drain_until(Nanos now);
  /// What each rule did so far (a copy: the nodes' thread may be counting).
  std::vector<FaultCount> counts() const;

 private:
  bool matches(std::size_t rule, const std::string& node, std::uint32_t id) const;
  double uniform();

  std::uint32_t target_id(const FaultRule& rule) const;  // the message a rule targets, or kNoId

  std::vector<FaultRule> rules_;
  std::atomic<std::size_t> rule_count_{0};  // read without the lock: no rules, no work per frame
  std::shared_ptr<const frames::MessageSet> set_;
  std::vector<std::string> node_names_;
  std::vector<std::uint32_t> rule_ids_;  ///< the message id of a message rule; kNoId otherwise
  std::vector<FaultCount> counts_;
  std::uint64_t state_;
  std::uint32_t bit_rate_;
  mutable PiMutex mutex_;  // on_send comes from the node threads (SCHED_FIFO), battery_drain_until from the physics
  Nanos start_{0};
  Nanos drained_until_{0};
  bool errors_on_wire_ = false;
};

/// Node names as written in rules: spaces become underscores ("FTT master" -> FTT_master).
std::string fault_node_name(std::string_view node);

}  // namespace canhil::can_nodes
