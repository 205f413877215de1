// tests/support/driving_laptop.hpp — a laptop played by a vcan test against
// a real-time run: on its own socket and thread it sends M6 (0.5 m/s
// forward) in every synchronous slot a trigger message gives it, and counts
// the trigger messages and the frames of one id it watches. Plus the loop
// that runs a RealtimeDriver until something is true, and the one-robot
// session they drive.
#pragma once

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "canhil/can_nodes/socketcan_bus.hpp"
#include "canhil/emulator/realtime_driver.hpp"
#include "canhil/frames/messages.hpp"
#include "support/test_paths.hpp"

namespace canhil::test {

class DrivingLaptop {
 public:
  DrivingLaptop(const std::string& interface, const frames::MessageSet& set, std::uint32_t watched_id)
      : bus_(can_nodes::SocketCanBus::open(interface)),
        set_(set),
        watched_id_(watched_id),
        thread_([this] { loop(); }) {}
  ~DrivingLaptop() { stop(); }
  DrivingLaptop(const DrivingLaptop&) = delete;
  DrivingLaptop& operator=(const DrivingLaptop&) = delete;

  /// Ends the thread (idempotent); the counts stay.
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  int tms() const { return tms_; }
  int watched() const { return watched_; }

 private:
  void loop() {
    using namespace std::chrono_literals;
    while (!stop_) {
      if (!bus_->wait_readable(20ms)) continue;
      while (auto f = bus_->receive()) {
        frames::Tm tm;
        if (frames::is_message(f->frame, set_.tm.message()) && set_.tm.decode(f->frame, tm).ok()) {
          ++tms_;
          if ((tm.sync_bitmap & (1U << set_.ftt(set_.m6_1.message()).index)) != 0) {
            bus_->send(set_.m6_1.encode(frames::M6_1{0, 0.5}));
            bus_->send(set_.m6_2.encode(frames::M6_2{}));
          }
        } else if (f->frame.id == watched_id_) {
          ++watched_;
        }
      }
    }
  }

  std::unique_ptr<can_nodes::SocketCanBus> bus_;
  const frames::MessageSet& set_;
  std::uint32_t watched_id_;
  std::atomic<bool> stop_{false};
  std::atomic<int> tms_{0};
  std::atomic<int> watched_{0};
  std::thread thread_;  // last: it starts once everything it uses is ready
};

/// One robot at (-3, 0) facing +x on vcan0, the ball out of its way, no
/// vision: the scenario the vcan tests' laptop drives.
inline emulator::Scenario one_robot_on_vcan0() {
  emulator::Scenario s;
  s.world.robots = {physics::Placement{-3.0, 0.0, -90}};
  s.world.ball_start = {3.0, 3.0, s.world.ball.radius_m};
  s.interfaces = {"vcan0"};
  return s;
}

/// The shipped DBC, no vision.
inline emulator::SessionOptions without_vision() {
  emulator::SessionOptions o;
  o.messages = frames::MessageSet::load(shipped_dbc());
  o.vision_on = false;
  return o;
}

/// Runs `driver` in 100 ms slices until `done()` or `limit` of its clock has passed; done()'s last word.
template <class Done>
bool run_until(emulator::RealtimeDriver& driver, Done done, Nanos limit) {
  using namespace std::chrono_literals;
  static std::atomic<bool> never{false};
  const Nanos end = driver.clock().now() + limit;
  while (!done() && driver.clock().now() < end) driver.run_until(driver.clock().now() + 100ms, never);
  return done();
}

}  // namespace canhil::test
