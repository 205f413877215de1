// The JSON commands a running session takes from outside: each one's effect
// at the next step, the reply, and hostile or mistaken requests refused with
// a reason and nothing changed.
#include "canhil/control/commands.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "canhil/emulator/virtual_driver.hpp"
#include "support/counter_watch.hpp"
#include "support/test_paths.hpp"

namespace canhil::control {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

class CommandsTest : public test::WatchedTest {
 protected:
  CommandsTest() {
    setenv("RTDB_KEY", std::to_string(0x5E100000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    scenario_.world.robots = {physics::Placement{-3.0, 0.0, -90}, physics::Placement{2.0, 2.0, 0}};
    scenario_.world.obstacles = {physics::ObstaclePlacement{{0, -3, 0}, {}}};
    options_.messages = frames::MessageSet::load(test::shipped_dbc());
    session_ = std::make_unique<emulator::Session>(emulator::plan_run(scenario_, options_));
    driver_ = std::make_unique<emulator::VirtualDriver>(*session_);
    commands_ = std::make_unique<Commands>(*session_);
    // Silent trouble in the robots' nodes fails the test (TearDown), the driver still there.
    for (std::size_t r = 0; r < session_->robot_count(); ++r) {
      counters.watch_nodes(*session_->rig(r).nodes, session_->rig(r).interface + ".");
    }
  }
  json send(const std::string& text) { return json::parse(commands_->handle(text)); }
  json step_and_snapshot() {
    driver_->run_for(10ms);
    return send(R"({"command":"snapshot"})")["snapshot"];
  }
  emulator::Scenario scenario_;
  emulator::SessionOptions options_;
  std::unique_ptr<emulator::Session> session_;
  std::unique_ptr<emulator::VirtualDriver> driver_;
  std::unique_ptr<Commands> commands_;
};

TEST_F(CommandsTest, MovesLandAtTheNextStepAndTheReplyEchoesTheId) {
  json r = send(R"({"command":"move_robot","robot":1,"x":4.5,"y":-1.5,"heading_deg":45,"id":7})");
  EXPECT_EQ(r["ok"], true) << r;
  EXPECT_EQ(r["id"], 7);
  EXPECT_EQ(send(R"({"command":"move_ball","x":1,"y":2,"vx":0.5})")["ok"], true);
  EXPECT_EQ(send(R"({"command":"move_obstacle","obstacle":0,"x":3,"y":3})")["ok"], true);
  const json s = step_and_snapshot();
  EXPECT_NEAR(s["robots"][1]["x"].get<double>(), 4.5, 0.01);
  EXPECT_NEAR(s["robots"][1]["heading_deg"].get<double>(), 45, 0.5);
  EXPECT_NEAR(s["ball"]["x"].get<double>(), 1.005, 0.003);
  EXPECT_NEAR(s["obstacles"][0]["y"].get<double>(), 3, 1e-9);
  EXPECT_EQ(s["steps"], 1);
}

TEST_F(CommandsTest, TheCoachAndFaultsGoThroughTheSessionToo) {
  EXPECT_EQ(send(R"({"command":"coach","game_state":"stop"})")["ok"], true);
  EXPECT_EQ(send(R"({"command":"coach","robot":1,"running":false,"role":"goalie"})")["ok"], true);
  EXPECT_EQ(send(R"({"command":"fault","rule":"drop:M8"})")["ok"], true);
  counters.allow_suffix(".fault_dropped");  // what the fault does
  const json s = step_and_snapshot();
  EXPECT_EQ(s["coach"]["game_state"], "stop");
  EXPECT_EQ(s["coach"]["players"][1]["running"], false);
  EXPECT_EQ(s["coach"]["players"][1]["role"], "goalie");
  EXPECT_EQ(s["coach"]["players"][0]["running"], true);
  driver_->run_for(1s);
  ASSERT_EQ(session_->fault_counts().size(), 1u);
  EXPECT_GT(session_->fault_counts()[0].applied, 0u);
}

TEST_F(CommandsTest, HostileAndMistakenRequestsAreRefusedAndChangeNothing) {
  const json before = send(R"({"command":"snapshot"})")["snapshot"];
  const std::string bad[] = {
      "",
      "not json",
      "[1,2,3]",
      R"({"cmd":"snapshot"})",
      R"({"command":42})",
      R"({"command":"explode"})",
      R"({"command":"move_robot","robot":0,"x":1,"y":1,"teleport":true})",
      R"({"command":"move_robot","robot":9,"x":1,"y":1})",
      R"({"command":"move_robot","robot":-1,"x":1,"y":1})",
      R"({"command":"move_robot","robot":0,"x":"far","y":1})",
      R"({"command":"move_robot","robot":0,"x":1e308,"y":1})",
      R"({"command":"move_ball","x":NaN,"y":1})",
      R"({"command":"move_ball","x":1,"y":1,"vx":1e9})",
      R"({"command":"move_obstacle","obstacle":3,"x":0,"y":0})",
      R"({"command":"fault","rule":"explode:M1"})",
      R"({"command":"fault","rule":"drop:Motor9"})",
      R"({"command":"coach","game_state":"dance"})",
      R"({"command":"coach","running":false})",
      R"({"command":"coach","robot":0,"running":"no"})",
      std::string(200, '[') + std::string(200, ']'),
      "{\"command\":\"snapshot\",\"pad\":\"" + std::string(70 * 1024, 'x') + "\"}",
      "{\"command\":\"move_ball\",\"x\":1,\"y\":\"\xff\xfe\"}",
  };
  for (const std::string& text : bad) {
    const json r = send(text);
    EXPECT_EQ(r["ok"], false) << text.substr(0, 80);
    EXPECT_TRUE(r["error"].is_string() && !r["error"].get<std::string>().empty()) << r;
  }
  EXPECT_EQ(commands_->refused(), std::size(bad));
  json after = step_and_snapshot();
  for (std::size_t r = 0; r < 2; ++r) {
    for (const char* k : {"x", "y", "heading_deg"}) {
      EXPECT_NEAR(after["robots"][r][k].get<double>(), before["robots"][r][k].get<double>(), 1e-6) << "nothing moved";
    }
  }
  EXPECT_NEAR(after["ball"]["x"].get<double>(), before["ball"]["x"].get<double>(), 1e-6);
  EXPECT_EQ(after["coach"], before["coach"]);
  EXPECT_TRUE(session_->fault_counts().empty());
}

TEST_F(CommandsTest, AFloodOfChangesIsBoundedNotQueuedForever) {
  std::size_t refused = 0;
  for (std::size_t k = 0; k < emulator::Session::kMaxPendingChanges + 10; ++k) {
    if (send(R"({"command":"move_ball","x":0,"y":0})")["ok"] == false) ++refused;
  }
  EXPECT_EQ(refused, 10u) << "beyond the limit, refused with a reason";
  driver_->run_for(10ms);
  EXPECT_EQ(send(R"({"command":"move_ball","x":0,"y":0})")["ok"], true) << "a step empties the queue";
}

}  // namespace
}  // namespace canhil::control
