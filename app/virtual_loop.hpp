// app/virtual_loop.hpp — the loop that drives a virtual-time run by its
// RunControl (pause, step, speed from the viewer or the control socket): as
// far as each plan says, and while the run stands, the session still takes
// changes (a robot dragged while paused moves). `canhil run` and `canhil
// bench --part view` both use it.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

#include "canhil/emulator/run_control.hpp"
#include "canhil/emulator/virtual_driver.hpp"

namespace canhil::app {

/// Runs until `end` or `stop`; `each_second` after every whole virtual second passed (and at the end).
inline void drive_virtual(emulator::VirtualDriver& driver, emulator::Session& session, emulator::RunControl& control,
                          Nanos end, const std::atomic<bool>& stop, const std::function<void()>& each_second = {}) {
  Nanos next_report = std::chrono::seconds(1);
  while (driver.now() < end && !stop) {
    const Nanos wall = std::chrono::steady_clock::now().time_since_epoch();
    const emulator::RunControl::Plan plan = control.next(driver.now(), wall, end);
    if (plan.run_to <= driver.now()) {
      session.settle();
      control.wait(std::min<Nanos>(plan.wall_wait, std::chrono::milliseconds(100)));
      continue;
    }
    driver.run_until(plan.run_to);
    if (driver.now() < next_report && driver.now() < end) continue;
    while (next_report <= driver.now()) next_report += std::chrono::seconds(1);
    if (each_second) each_second();
  }
}

}  // namespace canhil::app
