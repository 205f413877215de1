// The viewer's server without a browser: a WebSocket client written apart
// from the server's library (viewer::PageClient, plain sockets) against a
// running session in virtual time. The hello,
// the state stream and its rate, every command and its effect on the world,
// hostile messages refused with nothing changed, and the HTTP side: files
// only from the page's folder, the token, the origin check.
#include "canhil/viewer/server.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <future>

#include "canhil/control/run_commands.hpp"
#include "canhil/control/save_commands.hpp"
#include "canhil/emulator/virtual_driver.hpp"
#include "canhil/viewer/live_feed.hpp"
#include "canhil/viewer/page_client.hpp"
#include "support/counter_watch.hpp"
#include "support/test_paths.hpp"

namespace canhil::viewer {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

// A page, as far as the protocol goes.
class Client {
 public:
  explicit Client(std::uint16_t port, const std::string& target = "/ws", const std::string& origin = "")
      : page_(port, target, origin) {}
  void send(const std::string& text) { page_.send_text(text); }
  void send_binary(const std::string& bytes) { page_.send_binary(bytes); }
  json next() { return json::parse(page_.receive(5s)); }
  // The next message of this type (others are skipped: states keep coming).
  json next(const std::string& type) {
    for (int i = 0; i < 1000; ++i) {
      json m = next();
      if (m["type"] == type) return m;
    }
    ADD_FAILURE() << "no " << type << " message";
    return {};
  }
  json ask(json request) {
    static int id = 0;
    request["id"] = ++id;
    send(request.dump());
    for (int i = 0; i < 1000; ++i) {
      json m = next("reply");
      if (m["id"] == id) return m;
    }
    return {};
  }

 private:
  PageClient page_;
};

// GET target -> (status, body)
std::pair<int, std::string> get(std::uint16_t port, const std::string& target) { return http_get(port, target); }

class ViewerServerTest : public test::WatchedTest {
 protected:
  ViewerServerTest() {
    setenv("RTDB_KEY", std::to_string(0x5E300000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    dir_ = std::filesystem::temp_directory_path() / ("canhil-viewer-test-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir_ / "web" / "lib");
    std::ofstream(dir_ / "web" / "index.html") << "<html>page</html>";
    std::ofstream(dir_ / "web" / "lib" / "x.js") << "var x;";
    std::ofstream(dir_ / "secret.txt") << "secret";
    std::filesystem::create_symlink(dir_ / "secret.txt", dir_ / "web" / "link.txt");
    std::ofstream(dir_ / "web" / ".hidden") << "hidden";
    emulator::Scenario sc;
    sc.world.robots = {physics::Placement{-3.0, 0.0, -90}, physics::Placement{2.0, 2.0, 0}};
    sc.world.obstacles = {physics::ObstaclePlacement{{0, -3, 0}, {}}};
    emulator::SessionOptions o;
    o.messages = frames::MessageSet::load(test::shipped_dbc());
    session_ = std::make_unique<emulator::Session>(emulator::plan_run(sc, o));
    driver_ = std::make_unique<emulator::VirtualDriver>(*session_);
    commands_ = std::make_unique<control::Commands>(*session_);
    // Silent trouble in the robots' nodes fails the test (TearDown), the driver still there.
    for (std::size_t r = 0; r < session_->robot_count(); ++r) {
      counters.watch_nodes(*session_->rig(r).nodes, session_->rig(r).interface + ".");
    }
    clock_ = std::make_unique<emulator::RunControl>(o.ftt.elementary_cycle, 0, /*paused=*/true);
    control::add_run_commands(*commands_, *clock_);
    control::add_save_commands(*commands_, *session_, dir_ / "saves");
    commands_->on_done([this](const std::string& line) {
      if (server_) server_->log(line);
    });
    feed_ = std::make_unique<LiveFeed>(*session_, *commands_, clock_.get(), dir_ / "saves");
  }
  ~ViewerServerTest() override {
    server_.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  void serve(std::string token = "", double hz = 30) {
    ServerOptions o;
    o.port = 0;
    o.web_root = dir_ / "web";
    o.token = std::move(token);
    o.stream_hz = hz;
    server_ = std::make_unique<Server>(o, *feed_);
  }
  // One EC on the test's thread, as the run's loop would.
  void step() { driver_->run_for(10ms); }
  json snapshot() { return control::to_json(session_->snapshot()); }

  std::filesystem::path dir_;
  std::unique_ptr<emulator::Session> session_;
  std::unique_ptr<emulator::VirtualDriver> driver_;
  std::unique_ptr<control::Commands> commands_;
  std::unique_ptr<emulator::RunControl> clock_;
  std::unique_ptr<LiveFeed> feed_;
  std::unique_ptr<Server> server_;
};

TEST_F(ViewerServerTest, AHelloFirstThenTheWorldStreamedAtMostAtTheStreamRate) {
  serve("", 20);
  Client page(server_->port());
  const json hello = page.next();
  EXPECT_EQ(hello["type"], "hello");
  EXPECT_EQ(hello["mode"], "live");
  EXPECT_EQ(hello["field"]["length_m"], 18.0);
  ASSERT_EQ(hello["robots"].size(), 2u);
  EXPECT_EQ(hello["robots"][1]["agent"], 2);
  EXPECT_EQ(hello["robots"][1]["interface"], "vcan1");
  EXPECT_EQ(hello["obstacles"].size(), 1u);
  EXPECT_EQ(hello["ec_s"], 0.01);
  EXPECT_EQ(hello["virtual_time"], true);
  for (const auto& f : hello["faults"]) EXPECT_NO_THROW(can_nodes::parse_fault(f.get<std::string>())) << f;
  const json first = page.next();
  EXPECT_EQ(first["type"], "state");
  EXPECT_EQ(first["paused"], true);
  EXPECT_NEAR(first["robots"][0]["x"].get<double>(), -3.0, 1e-6);
  // Over one second at 20 Hz: about 20 states, never many more.
  const auto start = std::chrono::steady_clock::now();
  int states = 0;
  while (std::chrono::steady_clock::now() - start < 1s) states += page.next()["type"] == "state" ? 1 : 0;
  EXPECT_LE(states, 24);
  EXPECT_GE(states, 5);  // a loaded machine may give fewer; none would be a broken stream
}

TEST_F(ViewerServerTest, EveryCommandChangesTheWorldAsTheScenarioWouldAndIsLogged) {
  serve();
  Client page(server_->port());
  EXPECT_EQ(page.ask({{"command", "move_robot"}, {"robot", 1}, {"x", 4.0}, {"y", -1.0}, {"heading_deg", 30}})["ok"],
            true);
  EXPECT_EQ(page.next("log")["text"], "viewer: move_robot heading_deg=30 robot=1 x=4.0 y=-1.0");
  EXPECT_EQ(page.ask({{"command", "move_ball"}, {"x", 1.0}, {"y", 2.0}, {"vx", 3.0}, {"vy", 4.0}})["ok"], true);
  EXPECT_EQ(page.ask({{"command", "move_obstacle"}, {"obstacle", 0}, {"x", 5.0}, {"y", 5.0}})["ok"], true);
  EXPECT_EQ(page.ask({{"command", "coach"}, {"game_state", "our_kickoff"}})["ok"], true);
  EXPECT_EQ(page.ask({{"command", "fault"}, {"rule", "drop:M4_1:1"}})["ok"], true);
  counters.allow_suffix(".fault_dropped");  // what the fault does
  step();
  const json s = snapshot();
  EXPECT_NEAR(s["robots"][1]["x"].get<double>(), 4.0, 0.01);
  EXPECT_NEAR(s["robots"][1]["heading_deg"].get<double>(), 30, 0.5);
  EXPECT_NEAR(s["ball"]["x"].get<double>(), 1.0 + 3.0 * 0.01, 0.01);
  EXPECT_NEAR(s["ball_velocity"]["y"].get<double>(), 4.0, 0.2);
  EXPECT_NEAR(s["obstacles"][0]["x"].get<double>(), 5.0, 1e-9);
  EXPECT_EQ(s["coach"]["game_state"], "our_kickoff");
  bool fault_in = false;
  for (const auto& c : session_->fault_counts()) fault_in |= c.rule == "drop:M4_1:1";
  EXPECT_TRUE(fault_in);
  // The run's clock: pause and step through RunControl, speed too.
  EXPECT_EQ(page.ask({{"command", "step"}, {"count", 2}})["ok"], true);
  const auto p1 = clock_->next(driver_->now(), Nanos{0}, std::chrono::seconds(10));
  EXPECT_EQ(p1.run_to, driver_->now() + 10ms);
  EXPECT_EQ(page.ask({{"command", "resume"}})["ok"], true);
  EXPECT_FALSE(clock_->paused());
  EXPECT_EQ(page.ask({{"command", "speed"}, {"factor", 10}})["ok"], true);
  EXPECT_EQ(clock_->speed(), 10);
  EXPECT_EQ(page.ask({{"command", "pause"}})["ok"], true);
  EXPECT_TRUE(clock_->paused());
  // A robot's vision points, once watched, in the streamed state.
  EXPECT_EQ(page.ask({{"command", "watch_vision"}, {"robot", 0}})["ok"], true);
  driver_->run_for(100ms);
  json state;
  // Details are worked out at the next step or settle after a page asked (a paused run's loop settles).
  for (int i = 0; i < 200 && !state.contains("vision"); ++i) {
    session_->settle();
    state = page.next("state");
  }
  ASSERT_TRUE(state.contains("vision"));
  EXPECT_EQ(state["vision"]["robot"], 0);
  EXPECT_GT(state["vision"]["lines"].size(), 10u);
  EXPECT_TRUE(state["robots"][0].contains("achieved"));
  EXPECT_EQ(state["buses"].size(), 2u);
}

TEST_F(ViewerServerTest, HostileOrMistakenMessagesGetAnErrorReplyAndChangeNothing) {
  serve();
  Client page(server_->port());
  step();
  const json before = snapshot();
  const std::vector<std::string> bad = {
      "{not json",
      "[1,2,3]",
      R"({"command":"launch_missiles"})",
      R"({"command":"move_robot","robot":"one","x":0,"y":0})",
      R"({"command":"move_robot","robot":9,"x":0,"y":0})",
      R"({"command":"move_robot","robot":0,"x":1e999,"y":0})",
      R"({"command":"move_ball","x":0,"y":0,"vx":-1e308})",
      R"({"command":"move_robot","robot":0,"x":0,"y":0,"colour":"red"})",
      R"({"command":"coach","game_state":"win"})",
      R"({"command":"fault","rule":"melt:M1"})",
      R"({"command":"save","name":"../../etc/passwd","kind":"scenario"})",
      R"({"command":"load","name":"nothing-here","kind":"snapshot"})",
      R"({"command":"speed","factor":-3})",
      R"({"command":"snapshot","detail":"yes"})",
      R"({"command":"step"})",  // paused: fine; the next line un-pauses
      std::string(70 * 1024, ' ') + "{}",
      std::string(100, '[') + std::string(100, ']'),
  };
  int refused = 0;
  for (const std::string& b : bad) {
    page.send(b);
    const json r = page.next("reply");
    if (r["ok"] == false) {
      ++refused;
      EXPECT_FALSE(r["error"].get<std::string>().empty()) << b.substr(0, 80);
    }
  }
  EXPECT_EQ(refused, static_cast<int>(bad.size()) - 1);  // all but the step
  page.send_binary("\x01\x02");
  EXPECT_EQ(page.next("reply")["ok"], false);
  const json after = snapshot();
  EXPECT_EQ(after["robots"], before["robots"]);
  EXPECT_EQ(after["ball"], before["ball"]);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "etc"));
  // The page is still served.
  EXPECT_EQ(page.ask({{"command", "snapshot"}})["ok"], true);
}

TEST_F(ViewerServerTest, FilesOnlyFromThePagesFolder) {
  serve();
  const auto port = server_->port();
  EXPECT_EQ(get(port, "/"), std::make_pair(200, std::string("<html>page</html>")));
  EXPECT_EQ(get(port, "/lib/x.js").first, 200);
  EXPECT_EQ(get(port, "/../secret.txt").first, 403);
  EXPECT_EQ(get(port, "/%2e%2e/secret.txt").first, 403);
  EXPECT_EQ(get(port, "/lib/..%2f..%2fsecret.txt").first, 403);
  EXPECT_EQ(get(port, "/link.txt").first, 403);  // a link out of the folder
  EXPECT_EQ(get(port, "/.hidden").first, 403);
  EXPECT_EQ(get(port, "/nothing.js").first, 404);  // inside the folder, just not there
  EXPECT_EQ(get(port, "/api/replay").first, 404);  // a live run has no replay
  EXPECT_GE(server_->counters().http_refused, 7u);
}

TEST_F(ViewerServerTest, BeyondLoopbackTheTokenIsNeededAndAForeignPageIsRefused) {
  serve("abc123");
  const auto port = server_->port();
  EXPECT_THROW(Client(port, "/ws"), PageClientError);
  EXPECT_THROW(Client(port, "/ws?token=wrong"), PageClientError);
  EXPECT_THROW(Client(port, "/ws?token=abc123", "http://evil.example"), PageClientError);
  Client ok(port, "/ws?token=abc123", "http://127.0.0.1:" + std::to_string(port));
  EXPECT_EQ(ok.next()["type"], "hello");
  EXPECT_EQ(get(port, "/api/replay").first, 403);
  EXPECT_NE(server_->url().find("?token=abc123"), std::string::npos);
}

TEST_F(ViewerServerTest, SavedScenariosAndSnapshotsLoadBackWhileRunning) {
  serve();
  Client page(server_->port());
  page.ask({{"command", "move_robot"}, {"robot", 0}, {"x", 1.5}, {"y", -2.5}, {"heading_deg", 10}});
  page.ask({{"command", "move_ball"}, {"x", 3.0}, {"y", 1.0}});
  step();
  EXPECT_EQ(page.ask({{"command", "save"}, {"name", "corner"}, {"kind", "scenario"}})["ok"], true);
  // A snapshot is taken at a step: the test's loop steps while the page waits.
  auto saving = std::async(std::launch::async, [&] {
    return page.ask({{"command", "save"}, {"name", "corner-snap"}, {"kind", "snapshot"}});
  });
  while (saving.wait_for(5ms) != std::future_status::ready) step();
  EXPECT_EQ(saving.get()["ok"], true);
  const json listed = page.ask({{"command", "saves"}});
  ASSERT_EQ(listed["saves"].size(), 2u);
  EXPECT_EQ(listed["saves"][0]["name"], "corner");
  EXPECT_EQ(listed["saves"][1]["kind"], "snapshot");
  // The saved scenario is one canhil run --config reads.
  const emulator::Scenario reread = emulator::load_scenario(dir_ / "saves" / "corner.toml");
  EXPECT_NEAR(reread.world.robots[0].x_m, 1.5, 0.01);
  EXPECT_NEAR(reread.world.ball_start.x_m, 3.0, 0.01);
  EXPECT_EQ(reread.world.obstacles.size(), 1u);

  page.ask({{"command", "move_robot"}, {"robot", 0}, {"x", -6.0}, {"y", 4.0}, {"heading_deg", 0}});
  step();
  EXPECT_EQ(page.ask({{"command", "load"}, {"name", "corner"}, {"kind", "scenario"}})["ok"], true);
  step();
  EXPECT_NEAR(snapshot()["robots"][0]["x"].get<double>(), 1.5, 0.01);
  EXPECT_NEAR(snapshot()["robots"][0]["y"].get<double>(), -2.5, 0.01);

  page.ask({{"command", "move_robot"}, {"robot", 0}, {"x", -6.0}, {"y", 4.0}, {"heading_deg", 0}});
  step();
  EXPECT_EQ(page.ask({{"command", "load"}, {"name", "corner-snap"}, {"kind", "snapshot"}})["ok"], true);
  step();
  EXPECT_NEAR(snapshot()["robots"][0]["x"].get<double>(), 1.5, 0.02);
  EXPECT_NEAR(snapshot()["ball"]["x"].get<double>(), 3.0, 0.02);
}

TEST_F(ViewerServerTest, APortTakenIsAClearError) {
  serve();
  ServerOptions o;
  o.port = server_->port();
  o.web_root = dir_ / "web";
  try {
    Server second(o, *feed_);
    FAIL() << "bound twice";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("--view-port"), std::string::npos) << e.what();
  }
  o.port = 0;
  o.web_root = dir_;  // no index.html
  EXPECT_THROW(Server(o, *feed_), SetupError);
}

}  // namespace
}  // namespace canhil::viewer
