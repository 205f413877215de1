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
//   snapshot [detail]                            the world as the last step left it
//   watch_vision {robot | null}                  a robot's vision points in the detailed snapshot
//   move_robot {robot, x, y, heading_deg}         metres, degrees (the scenario's units)
//   move_ball {x, y, [z], [vx, vy, vz]}           metres, m/s
//   move_obstacle {obstacle, x, y}
//   fault {rule}                                  a fault rule as --fault takes it
//   coach {game_state} | {robot, [running], [role]}   the base station's orders
//   (a driver adds its own: pause, resume, step, speed, run_commands.hpp;
//   the viewer its saves, save_commands.hpp; see Commands::add)
//
// Every command that changes the run is logged through on_done() ("viewer:
// move_robot robot=0 x=1 ..."), so the run's log shows what was done from outside.
//
// Hostile input is refused and changes nothing: not JSON, not an object, an
// unknown command or argument, a wrong type, a number that is not finite or
// outside the field, a request over kMaxRequestBytes. Thread-safe: handle()
// may be called from any thread (the session's apply() and snapshot() are).
#pragma once

#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "canhil/emulator/session.hpp"

namespace canhil::control {

inline constexpr std::size_t kMaxRequestBytes = std::size_t{64} * 1024;

class Commands {
 public:
  /// A command of the caller's (a driver's): arguments in, reply fields out;
  /// throws SetupError for a bad argument (the reply then says why).
  using Handler = std::function<nlohmann::json(const nlohmann::json& request)>;
  enum class Effect : std::uint8_t { kChanges, kReads };  ///< kReads: not logged

  /// `session` must outlive this.
  explicit Commands(emulator::Session& session);
  ~Commands();
  Commands(const Commands&) = delete;
  Commands& operator=(const Commands&) = delete;

  /// Adds (or replaces) a command; `arguments` lists the keys it accepts.
  void add(const std::string& name, std::vector<std::string> arguments, Handler handler,
           Effect effect = Effect::kChanges);
  /// Called with a line for every command that changed the run (any thread).
  void on_done(std::function<void(const std::string&)> log);
  /// One request, one reply (both JSON text, the reply on one line); `from`
  /// names the transport in the log ("control", "viewer").
  std::string handle(std::string_view request, std::string_view from = "control");
  /// The same, the reply as JSON.
  nlohmann::json handle_text(std::string_view request, std::string_view from = "control");
  /// The same on parsed JSON.
  nlohmann::json handle_json(const nlohmann::json& request, std::string_view from = "control");
  /// Requests refused so far (malformed or hostile).
  std::uint64_t refused() const noexcept { return refused_; }

 private:
  struct Entry {
    std::vector<std::string> arguments;
    Handler handler;
    Effect effect = Effect::kChanges;
  };
  /// The reply; `effect` is the command's when it was carried out.
  nlohmann::json dispatch(const nlohmann::json& request, Effect& effect);

  emulator::Session& session_;
  mutable std::mutex mutex_;  // the table (add() may come while requests are served)
  std::map<std::string, Entry> commands_;
  std::function<void(const std::string&)> log_;
  std::atomic<std::uint64_t> refused_{0};
};

/// The snapshot as JSON (what `snapshot` replies and the viewer streams).
nlohmann::json to_json(const emulator::WorldSnapshot& snapshot);

}  // namespace canhil::control
