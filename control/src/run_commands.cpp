#include "canhil/control/run_commands.hpp"

#include "arguments.hpp"

namespace canhil::control {

void add_run_commands(Commands& commands, emulator::RunControl& control) {
  commands.add("pause", {}, [&control](const json&) {
    control.pause();
    return json::object();
  });
  commands.add("resume", {}, [&control](const json&) {
    control.resume();
    return json::object();
  });
  commands.add("step", {"count"}, [&control](const json& r) {
    const double count = number_or(r, "count", 1, 1, 10000);
    if (count != static_cast<double>(static_cast<std::uint32_t>(count))) {
      throw SetupError("\"count\" is a whole number of elementary cycles");
    }
    control.step(static_cast<std::uint32_t>(count));
    return json::object();
  });
  commands.add("speed", {"factor"}, [&control](const json& r) {
    control.set_speed(number(r, "factor", 0, emulator::RunControl::kMaxSpeed));
    return json::object();
  });
  commands.add(
      "run_state", {},
      [&control](const json&) {
        return json{{"paused", control.paused()}, {"speed", control.speed()}};
      },
      Commands::Effect::kReads);
}

}  // namespace canhil::control
