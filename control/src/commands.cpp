#include "canhil/control/commands.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "canhil/base/setup_error.hpp"

namespace canhil::control {
namespace {

using nlohmann::json;

// Positions must be on or near the field: nothing a hostile number can put far away.
constexpr double kMaxCoordinateM = 50.0;
constexpr double kMaxSpeedMps = 40.0;

double number(const json& request, const char* key, double low, double high) {
  const auto it = request.find(key);
  if (it == request.end()) throw SetupError(std::string("give \"") + key + "\" (a number)");
  if (!it->is_number()) throw SetupError(std::string("\"") + key + "\" must be a number");
  const double v = it->get<double>();
  if (!std::isfinite(v) || v < low || v > high) {
    throw SetupError(std::string("\"") + key + "\" must be a number from " + std::to_string(low) + " to " +
                     std::to_string(high));
  }
  return v;
}

double number_or(const json& request, const char* key, double fallback, double low, double high) {
  return request.contains(key) ? number(request, key, low, high) : fallback;
}

std::size_t index(const json& request, const char* key) {
  const auto it = request.find(key);
  if (it == request.end() || !it->is_number_unsigned()) {
    throw SetupError(std::string("give \"") + key + "\" as a whole number, 0 or more");
  }
  const auto v = it->get<std::uint64_t>();
  if (v > 1000) throw SetupError(std::string("\"") + key + "\" is out of range");
  return static_cast<std::size_t>(v);
}

std::string text(const json& request, const char* key, std::size_t longest = 200) {
  const auto it = request.find(key);
  if (it == request.end() || !it->is_string()) throw SetupError(std::string("give \"") + key + "\" as a text");
  std::string v = it->get<std::string>();
  if (v.empty() || v.size() > longest) throw SetupError(std::string("\"") + key + "\" is empty or too long");
  return v;
}

// Deeper than this is refused before parsing (the parsed value's destruction recurses).
constexpr int kMaxNesting = 32;

bool nested_too_deep(std::string_view text) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxNesting) return true;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return false;
}

std::string dumped(const json& reply) { return reply.dump(-1, ' ', false, json::error_handler_t::replace); }

json error(const std::string& what, const json& request) {
  json reply = {{"ok", false}, {"error", what}};
  if (request.is_object() && request.contains("id")) reply["id"] = request["id"];
  return reply;
}

}  // namespace

json to_json(const emulator::WorldSnapshot& s) {
  json robots = json::array();
  for (const kinematics::Pose& p : s.robots) {
    robots.push_back({{"x", p.x_m}, {"y", p.y_m}, {"heading_deg", p.heading_rad * 180.0 / M_PI}});
  }
  json obstacles = json::array();
  for (const auto& o : s.obstacles) obstacles.push_back({{"x", o.x()}, {"y", o.y()}});
  json goals = json::array();
  for (const emulator::Goal& g : s.goals)
    goals.push_back({{"time_s", to_seconds(g.time)}, {"positive_x", g.positive_x}});
  json players = json::array();
  for (const emulator::CoachPlayer& p : s.coach.players) {
    players.push_back({{"running", p.running}, {"role", p.role}, {"role_auto", p.role_auto}});
  }
  return {{"time_s", s.time_s},
          {"steps", s.steps},
          {"ball", {{"x", s.ball.x()}, {"y", s.ball.y()}, {"z", s.ball.z()}}},
          {"ball_velocity", {{"x", s.ball_velocity.x()}, {"y", s.ball_velocity.y()}, {"z", s.ball_velocity.z()}}},
          {"robots", robots},
          {"obstacles", obstacles},
          {"goals", goals},
          {"coach", {{"game_state", s.coach.game_state}, {"players", players}}}};
}

Commands::Commands(emulator::Session& session) : session_(session) {
  add("snapshot", {}, [this](const json&) { return json{{"snapshot", to_json(session_.snapshot())}}; });
  add("move_robot", {"robot", "x", "y", "heading_deg"}, [this](const json& r) {
    session_.apply(
        emulator::MoveRobot{index(r, "robot"), physics::Placement{number(r, "x", -kMaxCoordinateM, kMaxCoordinateM),
                                                                  number(r, "y", -kMaxCoordinateM, kMaxCoordinateM),
                                                                  number_or(r, "heading_deg", 0, -3600, 3600)}});
    return json::object();
  });
  add("move_ball", {"x", "y", "z", "vx", "vy", "vz"}, [this](const json& r) {
    const double radius = session_.scenario().world.ball.radius_m;
    session_.apply(emulator::MoveBall{
        {number(r, "x", -kMaxCoordinateM, kMaxCoordinateM), number(r, "y", -kMaxCoordinateM, kMaxCoordinateM),
         number_or(r, "z", radius, radius, 10)},
        {number_or(r, "vx", 0, -kMaxSpeedMps, kMaxSpeedMps), number_or(r, "vy", 0, -kMaxSpeedMps, kMaxSpeedMps),
         number_or(r, "vz", 0, -kMaxSpeedMps, kMaxSpeedMps)}});
    return json::object();
  });
  add("move_obstacle", {"obstacle", "x", "y"}, [this](const json& r) {
    session_.apply(emulator::MoveObstacle{index(r, "obstacle"), number(r, "x", -kMaxCoordinateM, kMaxCoordinateM),
                                          number(r, "y", -kMaxCoordinateM, kMaxCoordinateM)});
    return json::object();
  });
  add("fault", {"rule"}, [this](const json& r) {
    session_.apply(emulator::InjectFault{can_nodes::parse_fault(text(r, "rule"))});
    return json::object();
  });
  add("coach", {"game_state", "robot", "running", "role"}, [this](const json& r) {
    emulator::SetCoach c;
    if (r.contains("game_state")) c.game_state = text(r, "game_state", 40);
    if (r.contains("robot")) c.robot = index(r, "robot");
    if (r.contains("running")) {
      if (!r["running"].is_boolean()) throw SetupError("\"running\" must be true or false");
      c.running = r["running"].get<bool>();
    }
    if (r.contains("role")) c.role = text(r, "role", 40);
    if (!c.game_state && !c.robot) throw SetupError("give \"game_state\", or \"robot\" with \"running\" or \"role\"");
    session_.apply(std::move(c));
    return json::object();
  });
}

Commands::~Commands() = default;

void Commands::add(const std::string& name, std::vector<std::string> arguments, Handler handler) {
  commands_[name] = Entry{std::move(arguments), std::move(handler)};
}

json Commands::handle_json(const json& request) {
  if (!request.is_object()) {
    ++refused_;
    return error("a request is a JSON object with a \"command\"", request);
  }
  const auto command = request.find("command");
  if (command == request.end() || !command->is_string()) {
    ++refused_;
    return error("give \"command\" as a text", request);
  }
  const auto entry = commands_.find(command->get<std::string>());
  if (entry == commands_.end()) {
    ++refused_;
    std::string list;
    for (const auto& [name, e] : commands_) list += (list.empty() ? "" : ", ") + name;
    return error("unknown command; the commands are " + list, request);
  }
  for (const auto& [key, value] : request.items()) {
    if (key == "command" || key == "id") continue;
    const auto& known = entry->second.arguments;
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      ++refused_;
      return error("\"" + entry->first + "\" takes no \"" + key + "\"", request);
    }
  }
  try {
    json reply = entry->second.handler(request);
    reply["ok"] = true;
    if (request.contains("id")) reply["id"] = request["id"];
    return reply;
  } catch (const SetupError& e) {
    ++refused_;
    return error(e.what(), request);
  }
}

std::string Commands::handle(std::string_view request) {
  if (request.size() > kMaxRequestBytes) {
    ++refused_;
    return dumped(error("the request is over " + std::to_string(kMaxRequestBytes) + " bytes", json()));
  }
  if (nested_too_deep(request)) {
    ++refused_;
    return dumped(error("the request nests deeper than " + std::to_string(kMaxNesting) + " levels", json()));
  }
  const json parsed = json::parse(request, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) {
    ++refused_;
    return dumped(error("the request is not JSON", json()));
  }
  return dumped(handle_json(parsed));
}

}  // namespace canhil::control
