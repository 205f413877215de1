#include "canhil/emulator/scenario.hpp"

#include <toml++/toml.h>
#include <algorithm>

#include "canhil/base/setup_error.hpp"
#include "canhil/physics/config.hpp"

namespace canhil::emulator {
namespace {

class RunReader {
 public:
  RunReader(const toml::table& run, const std::string& file) : run_(run), file_(file) {}
  [[noreturn]] void fail(const toml::node& at, const std::string& key, const std::string& what) const {
    throw physics::ConfigError(file_, static_cast<int>(at.source().begin.line), "run." + key, what);
  }
  const toml::node* get(const std::string& key) const { return run_.get(key); }
  const toml::array* array(const std::string& key) const {
    const toml::node* n = get(key);
    if (n == nullptr) return nullptr;
    if (!n->is_array()) fail(*n, key, "must be a list, e.g. " + key + " = [...]");
    return n->as_array();
  }

 private:
  const toml::table& run_;
  const std::string& file_;
};

}  // namespace

Scenario parse_scenario(std::string_view toml_text, const std::string& file_name) {
  Scenario s;
  s.world = physics::parse_world_params(toml_text, file_name, {"run"});
  const toml::table root = toml::parse(toml_text, file_name);  // valid: parse_world_params read it
  if (s.world.robots.empty()) s.world.robots.push_back(kDefaultPlacement);
  const std::size_t robots = s.world.robots.size();
  if (const toml::table* run = root["run"].as_table()) {
    const RunReader r(*run, file_name);
    for (const auto& [k, v] : *run) {
      static const std::vector<std::string> kKnown = {"duration_s", "seed",   "kick_power",
                                                      "interfaces", "agents", "faults"};
      if (std::find(kKnown.begin(), kKnown.end(), k.str()) == kKnown.end()) {
        r.fail(v, std::string(k.str()),
               "unknown field; known here: duration_s, seed, kick_power, interfaces, agents, faults");
      }
    }
    if (const toml::node* n = r.get("duration_s")) {
      const auto v = n->value<double>();
      if (!v || !(*v > 0)) r.fail(*n, "duration_s", "must be a number of seconds above 0");
      s.duration_s = *v;
    }
    if (const toml::node* n = r.get("seed")) {
      const auto v = n->value<std::int64_t>();
      if (!v || *v < 0 || !n->is_integer()) r.fail(*n, "seed", "must be a whole number, 0 or more");
      s.seed = static_cast<std::uint64_t>(*v);
    }
    if (const toml::node* n = r.get("kick_power")) {
      const auto v = n->value<std::int64_t>();
      if (!v || !n->is_integer() || *v < 0 || *v > s.world.robot.kicker.max_power) {
        r.fail(*n, "kick_power", "must be a whole number from 0 to robot.kicker.max_power");
      }
      s.kick_power = static_cast<int>(*v);
    }
    if (const toml::array* a = r.array("interfaces")) {
      for (const toml::node& e : *a) {
        const auto v = e.value<std::string>();
        if (!v || v->empty() || v->size() > 15) r.fail(e, "interfaces", "must be interface names such as \"vcan0\"");
        s.interfaces.push_back(*v);
      }
      if (s.interfaces.size() != robots) {
        r.fail(*r.get("interfaces"), "interfaces",
               "give one interface per robot: the file places " + std::to_string(robots) + " robot(s)");
      }
    }
    if (const toml::array* a = r.array("agents")) {
      for (const toml::node& e : *a) {
        const auto v = e.value<std::int64_t>();
        if (!v || !e.is_integer() || *v < kFirstAgent || *v > kLastAgent) {
          r.fail(e, "agents", "agent numbers are whole numbers 1..6");
        }
        if (std::count(s.agents.begin(), s.agents.end(), *v) != 0) {
          r.fail(e, "agents", "agent " + std::to_string(*v) + " appears twice; give each robot its own");
        }
        s.agents.push_back(static_cast<int>(*v));
      }
      if (s.agents.size() != robots) {
        r.fail(*r.get("agents"), "agents",
               "give one agent number per robot: the file places " + std::to_string(robots) + " robot(s)");
      }
    }
    if (const toml::array* a = r.array("faults")) {
      for (const toml::node& e : *a) {
        const auto v = e.value<std::string>();
        if (!v) r.fail(e, "faults", "must be a list of fault texts such as \"drop:M4_1:0.1\"");
        try {
          s.faults.push_back(can_nodes::parse_fault(*v));
        } catch (const SetupError& err) {
          r.fail(e, "faults", err.what());
        }
      }
    }
  }
  complete(s);
  return s;
}

void complete(Scenario& s) {
  if (s.world.robots.empty()) s.world.robots.push_back(kDefaultPlacement);
  const std::size_t robots = s.world.robots.size();
  if (robots > static_cast<std::size_t>(kLastAgent - kFirstAgent + 1)) {
    throw SetupError("a run takes at most " + std::to_string(kLastAgent - kFirstAgent + 1) +
                     " robots (agents CAMBADA_1..6); this one places " + std::to_string(robots));
  }
  if (s.interfaces.empty()) {
    for (std::size_t k = 0; k < robots; ++k) s.interfaces.push_back("vcan" + std::to_string(k));
  }
  if (s.agents.empty()) {
    for (std::size_t k = 0; k < robots; ++k) s.agents.push_back(kFirstAgent + static_cast<int>(k));
  }
  if (s.interfaces.size() != robots || s.agents.size() != robots) {
    throw SetupError("give one interface and one agent number per robot (" + std::to_string(robots) + " robots, " +
                     std::to_string(s.interfaces.size()) + " interfaces, " + std::to_string(s.agents.size()) +
                     " agents)");
  }
  for (const int a : s.agents) {
    if (a < kFirstAgent || a > kLastAgent) {
      throw SetupError("agent numbers are " + std::to_string(kFirstAgent) + ".." + std::to_string(kLastAgent) +
                       ", got " + std::to_string(a));
    }
    if (std::count(s.agents.begin(), s.agents.end(), a) > 1) {
      throw SetupError("agent " + std::to_string(a) + " is given to two robots; give each robot its own");
    }
  }
}

std::filesystem::path shipped_scenario(const std::string& name) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    fs::path installed = exe.parent_path().parent_path() / "share" / "canhil" / "scenarios" / name;
    if (fs::exists(installed, ec)) return installed;
  }
  return fs::path(CANHIL_SOURCE_SCENARIOS) / name;
}

Scenario load_scenario(const std::filesystem::path& path) {
  return parse_scenario(physics::read_config_file(path), path.string());
}

}  // namespace canhil::emulator
