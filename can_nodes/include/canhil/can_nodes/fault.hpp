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
//
// TARGET is a message name of the message set (M3_1, M1, TM), a node name
// (Motor1, Pic_base, "FTT master" written FTT_master) or * for every frame.
// Any rule may end in @SECONDS to start then, e.g. drop:M4_1:0.5@2. The
// injector draws from its own generator (SplitMix64) seeded by the run's seed,
// so the same rules and seed give the same faults on every machine.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "canhil/can_nodes/node.hpp"

namespace canhil::can_nodes {

enum class FaultKind { kDrop, kDelay, kCorrupt, kDuplicate, kSilence };

struct FaultRule {
  FaultKind kind = FaultKind::kDrop;
  std::string target = "*";
  double probability = 1.0;
  Nanos delay{0};    ///< kDelay
  int byte = 0;      ///< kCorrupt: 0..7
  int copies = 1;    ///< kDuplicate
  Nanos from{0};     ///< the rule applies from this time on
  std::string text;  ///< as written
};

/// Parses one rule; throws std::invalid_argument saying what is wrong and the syntax.
FaultRule parse_fault(std::string_view text);

/// What one rule did over a run.
struct FaultCount {
  std::string rule;
  std::uint64_t matched = 0;  ///< frames of its target sent while it was active
  std::uint64_t applied = 0;  ///< frames it changed
};

class FaultInjector final : public FaultHook {
 public:
  /// Throws std::invalid_argument when a target is neither a message nor a node name.
  FaultInjector(std::vector<FaultRule> rules, std::shared_ptr<const frames::MessageSet> set,
                const std::vector<std::string>& node_names, std::uint64_t seed);

  FaultDecision on_send(const std::string& node, const frames::CanFrame& frame, Nanos now) override;
  const std::vector<FaultCount>& counts() const noexcept { return counts_; }

 private:
  bool matches(std::size_t rule, const std::string& node, std::uint32_t id) const;
  double uniform();

  std::vector<FaultRule> rules_;
  std::shared_ptr<const frames::MessageSet> set_;
  std::vector<std::uint32_t> rule_ids_;  ///< the message id of a message rule; kNoId otherwise
  std::vector<FaultCount> counts_;
  std::uint64_t state_;
};

/// Node names as written in rules: spaces become underscores ("FTT master" -> FTT_master).
std::string fault_node_name(std::string_view node);

}  // namespace canhil::can_nodes
