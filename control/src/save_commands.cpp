#include "canhil/control/save_commands.hpp"

#include <algorithm>
#include <fstream>

#include "arguments.hpp"
#include "canhil/emulator/scenario_writer.hpp"
#include "canhil/physics/world.hpp"

namespace canhil::control {
namespace {

namespace fs = std::filesystem;

// How long a save waits for the run to step (a snapshot is taken on the stepping thread).
constexpr std::chrono::milliseconds kStateWait{3000};

std::string save_name(const json& r) {
  std::string name = text(r, "name", 64);
  const bool fine = name[0] != '.' && std::all_of(name.begin(), name.end(), [](char c) {
                      return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' || c == '.';
                    });
  if (!fine) throw SetupError("a name is 1..64 letters, digits, '-', '_' or '.', not starting with '.'");
  return name;
}

// "scenario" -> .toml, "snapshot" -> .world
std::string extension(const json& r) {
  const std::string kind = text(r, "kind", 16);
  if (kind == "scenario") return ".toml";
  if (kind == "snapshot") return ".world";
  throw SetupError("\"kind\" is \"scenario\" or \"snapshot\"");
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out.flush()) throw SetupError("cannot write " + path.string());
}

void load_scenario_into(emulator::Session& session, const fs::path& path) {
  const emulator::Scenario sc = emulator::load_scenario(path);
  const auto& w = sc.world;
  if (w.robots.size() != session.robot_count() || w.obstacles.size() != session.world().obstacle_count()) {
    throw SetupError(
        path.filename().string() + " has " + std::to_string(w.robots.size()) + " robot(s) and " +
        std::to_string(w.obstacles.size()) + " obstacle(s); this run has " + std::to_string(session.robot_count()) +
        " and " + std::to_string(session.world().obstacle_count()) + " (start a new run with --config to change them)");
  }
  // As the file would have placed them at the start: each a change like a drag from the viewer.
  for (std::size_t r = 0; r < w.robots.size(); ++r) session.apply(emulator::MoveRobot{r, w.robots[r]});
  for (std::size_t o = 0; o < w.obstacles.size(); ++o) {
    session.apply(emulator::MoveObstacle{o, w.obstacles[o].at.x_m, w.obstacles[o].at.y_m});
  }
  session.apply(emulator::MoveBall{{w.ball_start.x_m, w.ball_start.y_m, w.ball_start.z_m}, Eigen::Vector3d::Zero()});
  session.apply(emulator::SetCoach{sc.coach.game_state, std::nullopt, std::nullopt, std::nullopt, std::nullopt});
  for (std::size_t t = 0; t < sc.coach.team_game_states.size(); ++t) {
    session.apply(emulator::SetCoach{sc.coach.team_game_states[t], std::nullopt, std::nullopt, std::nullopt, t});
  }
  for (std::size_t r = 0; r < sc.coach.players.size(); ++r) {
    session.apply(
        emulator::SetCoach{std::nullopt, r, sc.coach.players[r].running, sc.coach.players[r].role, std::nullopt});
  }
}

}  // namespace

std::vector<std::pair<std::string, std::string>> list_saves(const fs::path& folder) {
  std::vector<std::pair<std::string, std::string>> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string ext = entry.path().extension().string();
    if (ext == ".toml") out.emplace_back(entry.path().stem().string(), "scenario");
    if (ext == ".world") out.emplace_back(entry.path().stem().string(), "snapshot");
  }
  std::sort(out.begin(), out.end());
  return out;
}

void add_save_commands(Commands& commands, emulator::Session& session, const fs::path& folder) {
  commands.add("save", {"name", "kind"}, [&session, folder](const json& r) {
    const fs::path path = folder / (save_name(r) + extension(r));
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw SetupError("cannot make the save folder " + folder.string() + ": " + ec.message());
    if (path.extension() == ".toml") {
      write_text(path, emulator::scenario_toml(session.scenario(), session.snapshot()));
    } else {
      const auto state = session.saved_state(kStateWait);
      if (!state) throw SetupError("the run is not stepping (has it ended?); a snapshot is taken at a step");
      physics::save_state(*state, path);
    }
    return json{{"path", fs::absolute(path).string()}};
  });
  commands.add(
      "saves", {},
      [folder](const json&) {
        json list = json::array();
        for (const auto& [name, kind] : list_saves(folder)) list.push_back({{"name", name}, {"kind", kind}});
        return json{{"saves", list}, {"folder", fs::absolute(folder).string()}};
      },
      Commands::Effect::kReads);
  commands.add("load", {"name", "kind"}, [&session, folder](const json& r) {
    const fs::path path = folder / (save_name(r) + extension(r));
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw SetupError("no save " + path.filename().string() + " in " + folder.string());
    if (path.extension() == ".toml") {
      load_scenario_into(session, path);
    } else {
      session.apply(emulator::RestoreWorld{physics::load_state(path)});
    }
    return json::object();
  });
}

}  // namespace canhil::control
