// canhil/control/commands.hpp — what may be asked of a running session from
// outside (canhil coach, the viewer, a script), as JSON: one request in, one
// reply out. Every command becomes one of the session's changes (a moved body
// is a physics state change like any other) or a read of its snapshot; the
// same code serves every transport (the control socket, the viewer's
// WebSocket).
//
//   request  {"command": NAME, ...arguments, "id": anything (echoed)}
//   reply    {"ok": true, ...} or {"ok": false, "error": "what is wrong; what to send"}
//
// Commands:
//   snapshot                                     the world as the last step left it
//   move_robot {robot, x, y, heading_deg}         metres, degrees (the scenario's units)
//   move_ball {x, y, [z], [vx, vy, vz]}           metres, m/s
//   move_obstacle {obstacle, x, y}
//   fault {rule}                                  a fault rule as --fault takes it
//   coach {game_state} | {robot, [running], [role]}   the base station's orders
//   (a driver adds its own: pause, resume, step, speed; see Commands::add)
//
// Hostile input is refused and changes nothing: not JSON, not an object, an
// unknown command or argument, a wrong type, a number that is not finite or
// outside the field, a request over kMaxRequestBytes. Thread-safe: handle()
// may be called from any thread (the session's apply() and snapshot() are).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "canhil/emulator/session.hpp"

namespace canhil::control {

inline constexpr std::size_t kMaxRequestBytes = 64 * 1024;

class Commands {
 public:
  /// A command of the caller's (a driver's): arguments in, reply fields out;
  /// throws SetupError for a bad argument (the reply then says why).
  using Handler = std::function<nlohmann::json(const nlohmann::json& request)>;

  /// `session` must outlive this.
  explicit Commands(emulator::Session& session);
  ~Commands();
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;

  /// Adds (or replaces) a command; `arguments` lists the keys it accepts.
  void add(const std::string& name, std::vector<std::string> arguments, Handler handler);
  /// One request, one reply (both JSON text, the reply on one line).
  std::string handle(std::string_view request);
  /// The same on parsed JSON.
  nlohmann::json handle_json(const nlohmann::json& request);
  /// Requests refused so far (malformed or hostile).
  std::uint64_t refused() const noexcept { return refused_; }

 private:
  struct Entry {
    std::vector<std::string> arguments;
    Handler handler;
  };
  emulator::Session& session_;
  std::map<std::string, Entry> commands_;
  std::atomic<std::uint64_t> refused_{0};
};

/// The snapshot as JSON (what `snapshot` replies and the viewer streams).
nlohmann::json to_json(const emulator::WorldSnapshot& snapshot);

}  // namespace canhil::control
