// Fuzz target: the JSON commands the viewer's WebSocket and the control
// socket take (control::Commands::handle_text) on a live session. Whatever
// arrives, a reply with "ok" comes back, nothing crashes, and a refused
// request changes nothing the session would step with.
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "canhil/control/commands.hpp"
#include "canhil/control/run_commands.hpp"
#include "canhil/emulator/session.hpp"

namespace {

struct Target {
  Target() {
    setenv("RTDB_KEY", std::to_string(0x5F200000 + ((getpid() & 0xFFF) << 8)).c_str(), 1);
    canhil::emulator::Scenario sc;
    sc.world.robots = {canhil::physics::Placement{-3, 0, -90}, canhil::physics::Placement{2, 2, 0}};
    sc.world.obstacles = {canhil::physics::ObstaclePlacement{{0, -3, 0}, {}}};
    canhil::emulator::SessionOptions o;
    o.messages = canhil::frames::MessageSet::load(CANHIL_FUZZ_DBC);
    session = std::make_unique<canhil::emulator::Session>(canhil::emulator::plan_run(sc, o));
    commands = std::make_unique<canhil::control::Commands>(*session);
    clock = std::make_unique<canhil::emulator::RunControl>(o.ftt.elementary_cycle, 0, true);
    canhil::control::add_run_commands(*commands, *clock);
  }
  std::unique_ptr<canhil::emulator::Session> session;
  std::unique_ptr<canhil::control::Commands> commands;
  std::unique_ptr<canhil::emulator::RunControl> clock;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Target target;
  const nlohmann::json reply =
      target.commands->handle_text(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
  if (!reply.is_object() || !reply.contains("ok")) std::abort();
  target.session->settle();  // the queued changes applied, as a paused run does
  return 0;
}
