// `canhil coach STATE | --robot N [--running yes|no] [--role ROLE] | status`:
// the base station's orders to a running `canhil run`, through its control
// socket (canhil/control/commands.hpp): the game state for every robot, or
// one robot's running flag and role. canhil writes them into every robot's
// RTDB as the team's base station would (COACH_INFO in the team's layout).
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>

#include "canhil/control/unix_server.hpp"
#include "canhil/emulator/coach.hpp"
#include "commands.hpp"

namespace canhil::app {
namespace {

nlohmann::json ask(const std::filesystem::path& socket, const nlohmann::json& request) {
  nlohmann::json reply = nlohmann::json::parse(control::send_request(socket, request.dump()), nullptr, false);
  if (reply.is_discarded() || !reply.is_object())
    throw SetupError("the run at " + socket.string() + " answered nonsense");
  if (!reply.value("ok", false)) throw UsageError("the run refused: " + reply.value("error", std::string("?")));
  return reply;
}

void print_status(const nlohmann::json& snapshot) {
  const auto& coach = snapshot["coach"];
  std::printf("game state: %s\n", coach.value("game_state", std::string("?")).c_str());
  int r = 0;
  for (const auto& p : coach["players"]) {
    std::printf("  robot %d: %s, role %s%s\n", r++, p.value("running", false) ? "running" : "stopped",
                p.value("role", std::string("?")).c_str(), p.value("role_auto", false) ? " (auto)" : "");
  }
}

// Whether the run's snapshot shows what `order` asked for.
bool taken(const nlohmann::json& snapshot, const nlohmann::json& order) {
  const nlohmann::json& coach = snapshot["coach"];
  if (order.contains("game_state") && coach.value("game_state", std::string()) != order["game_state"]) return false;
  if (!order.contains("robot")) return true;
  const auto r = order["robot"].get<std::size_t>();
  if (!coach["players"].is_array() || r >= coach["players"].size()) return false;
  const nlohmann::json& p = coach["players"][r];
  if (order.contains("running") && p.value("running", false) != order["running"].get<bool>()) return false;
  return !order.contains("role") || p.value("role", std::string()) == order["role"];
}

}  // namespace

int run_coach(Args& args, const std::optional<std::string>&) {
  const auto control = args.option("--control");
  const auto robot = optional_number(args, "--robot");
  const auto running = args.option("--running");
  const auto role = args.option("--role");
  const std::vector<std::string> words = args.positionals();
  const std::filesystem::path socket = control ? std::filesystem::path(*control) : control::default_socket_path();
  nlohmann::json request = {{"command", "coach"}};
  if (words.size() == 2 && words[1] == "status") {
    print_status(ask(socket, {{"command", "snapshot"}})["snapshot"]);
    return 0;
  }
  if (words.size() == 2) {
    if (!emulator::is_game_state(words[1])) {
      std::string list;
      for (const auto g : emulator::kGameStates) list += (list.empty() ? "" : ", ") + std::string(g);
      throw UsageError("\"" + words[1] + "\" is not a game state; use one of " + list + ", or status");
    }
    request["game_state"] = words[1];
  } else if (words.size() != 1) {
    throw UsageError("coach takes one game state (start, stop, our_kickoff, ...) or status");
  }
  if (robot) {
    if (!(*robot >= 0 && *robot == static_cast<double>(static_cast<int>(*robot)))) {
      throw UsageError("--robot takes a robot number, 0 or more");
    }
    request["robot"] = static_cast<int>(*robot);
  }
  if (running) {
    if (*running != "yes" && *running != "no") throw UsageError("--running takes yes or no");
    request["running"] = *running == "yes";
  }
  if (role) request["role"] = *role;
  if ((running || role) && !robot) throw UsageError("--running and --role need --robot N");
  if (request.size() == 1) throw UsageError("say what to order: a game state, or --robot N with --running or --role");
  ask(socket, request);
  // The order takes effect at the run's next step: show the state once it has
  // (a slow or loaded machine may take a while; say so if it has not).
  nlohmann::json snapshot;
  for (int i = 0; i < 250; ++i) {
    snapshot = ask(socket, {{"command", "snapshot"}})["snapshot"];
    if (taken(snapshot, request)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!taken(snapshot, request)) std::printf("ordered; the run has not taken it yet (it does at its next step)\n");
  print_status(snapshot);
  return 0;
}

}  // namespace canhil::app
