// canhil/can_nodes/nodes.hpp — the emulated microcontrollers of one robot.
//
// FttMaster     (on Pic_base)  TM at the start of every elementary cycle
// PicBase                      M6_1+M6_2 -> inverse kinematics -> M1; M7 -> kicker, grabber; M9; M2
// MotorNode x3                 M1 -> wheel speed at the 5 ms motor tick; M3_n every EC
// PicOdom                      M3_1..M3_3 -> forward kinematics -> M4_1, M4_2; M5 sets or resets the pose
// CompassNode                  M8
// SystemMonitor (on Pic_base)  M10: nodes alive (seen on the bus), bad-frame count, state
//
// Synchronous messages go out at the start of the synchronous window of every
// EC whose TM schedules them; asynchronous ones just after the TM, no faster
// than their minimum gap. Units and layouts: frames/messages.hpp.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <optional>

#include "canhil/base/periodic.hpp"
#include "canhil/can_nodes/node.hpp"
#include "canhil/can_nodes/node_ids.hpp"
#include "canhil/can_nodes/robot_io.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/kinematics/omni.hpp"

namespace canhil::can_nodes {

using namespace std::chrono_literals;

/// Firmware parameters; defaults as on the robot where known (docs/nodes.md).
struct NodeParams {
  frames::FttConfig ftt;
  kinematics::OmniGeometry geometry;  ///< must match the robot's
  kinematics::EncoderSpec encoder;
  Nanos watchdog = 150ms;                 ///< Pic_base: no M6 for longer -> brake
  Nanos motor_watchdog = 100ms;           ///< a motor node: no M1 for longer -> brake
  int max_setpoint = 900;                 ///< counts per motor tick
  double max_wheel_accel_radps2 = 60.0;   ///< Pic_base set-point slope (about 3.4 m/s^2 at the wheel)
  double fine_wheel_accel_radps2 = 15.0;  ///< the same with M6_2.small_adjustment = 1
  Nanos just_kicked_hold = 100ms;         ///< M9.just_kicked stays 1 this long after a kick
  Nanos alive_timeout = 200ms;            ///< system monitor: a node unseen this long is not alive
};

class FttMaster final : public Node {
 public:
  /// Sends the TM of EC k at first_ec + k * EC.
  FttMaster(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const frames::FttSchedule& schedule,
            Nanos first_ec);
  std::uint64_t ec_count() const noexcept { return ec_; }

 protected:
  void on_frame(const frames::TimedFrame&) override {}
  void step(Nanos now) override;

 private:
  const frames::FttSchedule& schedule_;
  Nanos first_ec_;
  std::uint64_t ec_ = 0;
};

class PicBase final : public Node {
 public:
  PicBase(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params, RobotIo& robot);
  /// True while braking because M6 stopped arriving.
  bool watchdog_tripped(Nanos now) const noexcept;
  const std::array<int, 3>& setpoints() const noexcept { return setpoints_; }
  /// The velocity the laptop last commanded (M6_1 and M6_2, robot frame), or
  /// nullopt before the first M6.
  std::optional<kinematics::Twist> commanded() const noexcept {
    if (last_m6_ == kLongAgo) return std::nullopt;
    return kinematics::Twist{m6_1_.vx, m6_1_.vy, m6_2_.va};
  }

 protected:
  void on_frame(const frames::TimedFrame& frame) override;
  void step(Nanos now) override;

 private:
  void send_m1(Nanos now);
  const NodeParams& params_;
  RobotIo& robot_;
  kinematics::OmniKinematics kinematics_;
  frames::SyncSlot slot_;
  frames::M6_1 m6_1_{};
  frames::M6_2 m6_2_{};
  Nanos last_m6_ = kLongAgo;
  std::array<int, 3> setpoints_{};
  std::array<double, 3> ramp_{};  // set points before rounding, counts per tick
  Nanos last_m1_ = kLongAgo;
  std::uint8_t m1_seq_ = 0;
  Nanos last_kick_ = kLongAgo;
  int grabber_ = 0;
  Nanos async_at_ = kNever;
  Nanos last_m2_ = kLongAgo;
};

class MotorNode final : public Node {
 public:
  /// `wheel` is 0..2 (Motor1..Motor3).
  MotorNode(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params, RobotIo& robot,
            int wheel, Nanos first_tick);

 protected:
  void on_frame(const frames::TimedFrame& frame) override;
  void step(Nanos now) override;

 private:
  const NodeParams& params_;
  RobotIo& robot_;
  int wheel_;
  frames::SyncSlot slot_;
  Periodic ticks_;  ///< the speed loop's ticks (encoder.motor_tick_s)
  int setpoint_ = 0;
  bool enable_ = false;
  Nanos last_m1_ = kLongAgo;
  std::int64_t last_reported_ = 0;
  bool reported_once_ = false;
  std::uint8_t seq_ = 0;
};

class PicOdom final : public Node {
 public:
  PicOdom(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params);
  const kinematics::Pose& pose() const noexcept { return pose_; }

 protected:
  void on_frame(const frames::TimedFrame& frame) override;
  void step(Nanos now) override;

 private:
  void integrate();
  const NodeParams& params_;
  kinematics::OmniKinematics kinematics_;
  frames::SyncSlot slot_;
  kinematics::Pose pose_;
  std::array<std::int32_t, 3> last_encoder_{};
  std::array<std::int32_t, 3> encoder_{};
  std::array<bool, 3> seen_{};   // an M3 from each motor since the last integration
  bool have_reference_ = false;  // last_encoder_ is valid
  std::optional<frames::M5_1> m5_1_;
  std::uint16_t seq_ = 0;
};

class CompassNode final : public Node {
 public:
  CompassNode(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params, RobotIo& robot);

 protected:
  void on_frame(const frames::TimedFrame& frame) override;
  void step(Nanos now) override;

 private:
  const NodeParams& params_;
  RobotIo& robot_;
  frames::SyncSlot slot_;
};

class SystemMonitor final : public Node {
 public:
  /// `bad_frames` reports the bad frames the other nodes have counted;
  /// `state` the node_state byte (see docs/nodes.md). With a `watch` bus the
  /// node takes only TMs on `bus` and watches the whole bus on `watch`, so
  /// that a flood of other frames (counted, and lost to overflow if need be)
  /// never costs it a TM; without, `bus` does both.
  SystemMonitor(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params,
                std::function<std::uint64_t()> bad_frames, std::function<std::uint8_t(Nanos)> state,
                Endpoint* watch = nullptr);
  /// alive bitmap as M10 reports it now.
  std::uint8_t alive(Nanos now) const noexcept;

 protected:
  void on_frame(const frames::TimedFrame& frame) override;
  void step(Nanos now) override;
  std::size_t poll_more(std::size_t max_frames) override;
  bool more_may_have_frames() const override { return watch_ != nullptr && watch_->may_have_frames(); }
  bool more_set_doorbell(const std::shared_ptr<Doorbell>& bell, std::size_t index) override {
    return watch_ == nullptr || watch_->set_doorbell(bell, index);
  }

 private:
  void observe(const frames::TimedFrame& frame);  // bad frames and who is alive
  const NodeParams& params_;
  Endpoint* watch_;
  std::function<std::uint64_t()> bad_frames_;
  std::function<std::uint8_t(Nanos)> state_;
  std::array<Nanos, 6> last_seen_;     // Pic_base, Motor1..3, Pic_odom, Compass
  std::vector<std::uint8_t> watched_;  // per message of the codec: its transmitter's index above, or kNotWatched
  static constexpr std::uint8_t kNotWatched = 0xFF;
  Nanos async_at_ = kNever;
  Nanos last_m10_ = kLongAgo;
};

}  // namespace canhil::can_nodes
