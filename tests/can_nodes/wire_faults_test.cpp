// The fault language's wire rules as the wire's own: targets by identifier
// or controller, times kept, nodes not on the bus left out.
#include "canhil/can_nodes/wire_faults.hpp"

#include <gtest/gtest.h>

#include "support/test_paths.hpp"

namespace canhil::can_nodes {
namespace {

using namespace std::chrono_literals;

TEST(WireFaultRules, EachRuleBecomesTheWiresWithItsTargetAndTimes) {
  const auto set = frames::MessageSet::load(test::shipped_dbc());
  std::vector<FaultRule> rules;
  for (const char* text : {"drop:M1", "ber:*:1e-4@1+2", "noack:M6_1", "busoff:laptop@3", "babble:Motor1:0x10",
                           "cut:Compass@2+0.5", "error:Motor2:0.5", "stuck:SysMon"}) {
    rules.push_back(parse_fault(text));
  }
  const ControllerOf controllers = [](std::string_view node) -> std::optional<wire::ControllerId> {
    if (node == "laptop") return 7;
    if (node == "Motor1") return 2;
    if (node == "Motor2") return 3;
    if (node == "Compass") return 5;
    return std::nullopt;  // SysMon: a real board, not on canhil's bus
  };
  const std::vector<wire::FaultRule> w = wire_rules(rules, *set, controllers);
  ASSERT_EQ(w.size(), 6u) << "drop is the injector's; SysMon is not on this bus";
  EXPECT_EQ(w[0].kind, wire::FaultRule::Kind::kBitErrors);
  EXPECT_DOUBLE_EQ(w[0].rate, 1e-4);
  EXPECT_EQ(w[0].from, 1s);
  EXPECT_EQ(w[0].until, 3s);
  EXPECT_FALSE(w[0].controller);
  EXPECT_EQ(w[1].kind, wire::FaultRule::Kind::kNoAck);
  EXPECT_EQ(w[1].id, std::optional<std::uint32_t>(set->codec().find("M6_1")->id()));
  EXPECT_EQ(w[2].kind, wire::FaultRule::Kind::kBusOff);
  EXPECT_EQ(w[2].controller, std::optional<wire::ControllerId>(7));
  EXPECT_EQ(w[2].from, 3s);
  EXPECT_EQ(w[3].kind, wire::FaultRule::Kind::kBabbling);
  EXPECT_EQ(w[3].babble.id, 0x10u);
  EXPECT_EQ(w[4].kind, wire::FaultRule::Kind::kCut);
  EXPECT_EQ(w[4].until, 2500ms);
  EXPECT_EQ(w[5].kind, wire::FaultRule::Kind::kFrameErrors) << "error, on a timed wire";
  EXPECT_DOUBLE_EQ(w[5].rate, 0.5);
  EXPECT_EQ(w[5].controller, std::optional<wire::ControllerId>(3));
}

}  // namespace
}  // namespace canhil::can_nodes
