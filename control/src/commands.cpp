#include "canhil/control/commands.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "arguments.hpp"
#include "canhil/base/setup_error.hpp"

namespace canhil::control {
namespace {

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

json pose_json(const kinematics::Pose& p) {
  return {{"x", p.x_m}, {"y", p.y_m}, {"heading_deg", p.heading_rad * 180.0 / M_PI}};
}

json twist_json(const kinematics::Twist& t) { return {{"vx", t.vx_mps}, {"vy", t.vy_mps}, {"w", t.va_radps}}; }

json points_json(const std::vector<Eigen::Vector2d>& points) {
  json out = json::array();
  for (const Eigen::Vector2d& p : points) out.push_back({p.x(), p.y()});
  return out;
}

// What a detailed snapshot adds: per robot its odometry, commanded and achieved
// velocity; per bus its load and jitter; the watched robot's vision.
void add_detail(json& out, const emulator::WorldSnapshot& s) {
  json& robots = out["robots"];
  for (std::size_t r = 0; r < s.detail.size() && r < robots.size(); ++r) {
    const emulator::RobotDetail& d = s.detail[r];
    robots[r]["odometry"] = d.odometry ? pose_json(*d.odometry) : json(nullptr);
    robots[r]["commanded"] = d.commanded ? twist_json(*d.commanded) : json(nullptr);
    robots[r]["achieved"] = twist_json(d.achieved);
  }
  json buses = json::array();
  json latency = json::array();
  for (const emulator::BusDetail& b : s.buses) {
    json jitter = json::object();
    for (const auto& [name, ms] : b.jitter_ms) jitter[name] = ms;
    buses.push_back({{"frames", b.frames}, {"load", b.load}, {"jitter_ms", jitter}});
    latency.push_back(b.handler_latency_ms ? json(*b.handler_latency_ms) : json(nullptr));
  }
  out["buses"] = buses;
  out["handler_latency_ms"] = latency;
  if (s.vision) {
    out["vision"] = {{"robot", s.vision->robot},
                     {"time_s", s.vision->time_s},
                     {"lines", points_json(s.vision->lines)},
                     {"obstacles", points_json(s.vision->obstacles)},
                     {"balls", points_json(s.vision->balls)}};
  }
}

}  // namespace

json to_json(const emulator::WorldSnapshot& s) {
  json robots = json::array();
  for (const kinematics::Pose& p : s.robots) robots.push_back(pose_json(p));
  json obstacles = json::array();
  for (const auto& o : s.obstacles) obstacles.push_back({{"x", o.x()}, {"y", o.y()}});
  json goals = json::array();
  for (const emulator::Goal& g : s.goals)
    goals.push_back({{"time_s", to_seconds(g.time)}, {"positive_x", g.positive_x}});
  json players = json::array();
  for (const emulator::CoachPlayer& p : s.coach.players) {
    players.push_back(
        {{"running", p.running}, {"role", p.role}, {"role_auto", p.role_auto}, {"relocations", p.relocations}});
  }
  json out = {{"time_s", s.time_s},
              {"steps", s.steps},
              {"ball", {{"x", s.ball.x()}, {"y", s.ball.y()}, {"z", s.ball.z()}}},
              {"ball_velocity", {{"x", s.ball_velocity.x()}, {"y", s.ball_velocity.y()}, {"z", s.ball_velocity.z()}}},
              {"robots", robots},
              {"obstacles", obstacles},
              {"goals", goals},
              {"coach", {{"game_state", s.coach.game_state}, {"players", players}}}};
  if (!s.detail.empty()) add_detail(out, s);
  return out;
}

Commands::Commands(emulator::Session& session) : session_(session) {
  add(
      "snapshot", {"detail"},
      [this](const json& r) {
        if (r.contains("detail") && !r["detail"].is_boolean()) throw SetupError("\"detail\" must be true or false");
        const bool detail = r.contains("detail") && r["detail"].get<bool>();
        return json{{"snapshot", to_json(detail ? session_.detailed_snapshot() : session_.snapshot())}};
      },
      Effect::kReads);
  add("watch_vision", {"robot"}, [this](const json& r) {
    if (!r.contains("robot")) throw SetupError("give \"robot\" (a robot's index, or null to stop)");
    session_.watch_vision(r["robot"].is_null() ? std::nullopt : std::optional<std::size_t>(index(r, "robot")));
    return json::object();
  });
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

void Commands::add(const std::string& name, std::vector<std::string> arguments, Handler handler, Effect effect) {
  const std::lock_guard lock(mutex_);
  commands_[name] = Entry{std::move(arguments), std::move(handler), effect};
}

void Commands::on_done(std::function<void(const std::string&)> log) {
  const std::lock_guard lock(mutex_);
  log_ = std::move(log);
}

static std::string describe_request(const json& request) {
  std::string line = request.value("command", std::string("?"));
  for (const auto& [key, value] : request.items()) {
    if (key == "command" || key == "id") continue;
    line += " " + key + "=" + (value.is_string() ? value.get<std::string>() : dumped(value));
  }
  return line;
}

json Commands::handle_json(const json& request, std::string_view from) {
  Effect effect = Effect::kReads;
  json reply = dispatch(request, effect);
  if (effect == Effect::kChanges && reply.value("ok", false)) {
    std::function<void(const std::string&)> log;
    {
      const std::lock_guard lock(mutex_);
      log = log_;
    }
    if (log) log(std::string(from) + ": " + describe_request(request));
  }
  return reply;
}

json Commands::dispatch(const json& request, Effect& effect) {
  if (!request.is_object()) {
    ++refused_;
    return error("a request is a JSON object with a \"command\"", request);
  }
  const auto command = request.find("command");
  if (command == request.end() || !command->is_string()) {
    ++refused_;
    return error("give \"command\" as a text", request);
  }
  Entry entry;
  {
    const std::lock_guard lock(mutex_);
    const auto found = commands_.find(command->get<std::string>());
    if (found == commands_.end()) {
      ++refused_;
      std::string list;
      for (const auto& [name, e] : commands_) list += (list.empty() ? "" : ", ") + name;
      return error("unknown command; the commands are " + list, request);
    }
    entry = found->second;
  }
  for (const auto& [key, value] : request.items()) {
    if (key == "command" || key == "id") continue;
    const auto& known = entry.arguments;
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      ++refused_;
      return error("\"" + command->get<std::string>() + "\" takes no \"" + key + "\"", request);
    }
  }
  try {
    json reply = entry.handler(request);
    effect = entry.effect;
    reply["ok"] = true;
    if (request.contains("id")) reply["id"] = request["id"];
    return reply;
  } catch (const SetupError& e) {
    ++refused_;
    return error(e.what(), request);
  }
}

json Commands::handle_text(std::string_view request, std::string_view from) {
  if (request.size() > kMaxRequestBytes) {
    ++refused_;
    return error("the request is over " + std::to_string(kMaxRequestBytes) + " bytes", json());
  }
  if (nested_too_deep(request)) {
    ++refused_;
    return error("the request nests deeper than " + std::to_string(kMaxNesting) + " levels", json());
  }
  const json parsed = json::parse(request, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) {
    ++refused_;
    return error("the request is not JSON", json());
  }
  return handle_json(parsed, from);
}

std::string Commands::handle(std::string_view request, std::string_view from) {
  return dumped(handle_text(request, from));
}

}  // namespace canhil::control
