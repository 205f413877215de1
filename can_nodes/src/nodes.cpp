#include "canhil/can_nodes/nodes.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/wire.hpp"

namespace canhil::can_nodes {
namespace {

using frames::CanFrame;
using frames::is_message;
using frames::TimedFrame;

std::vector<Filter> filters_for(const frames::MessageSet& set, std::initializer_list<const char*> names) {
  std::vector<Filter> f;
  for (const char* n : names) {
    if (const frames::MessageCodec* m = set.codec().find(n)) f.push_back(Filter::exact(m->id()));
  }
  return f;
}

Nanos tm_wire_time(const NodeParams& p) {
  return frames::bits_to_time(frames::worst_case_frame_bits(8), p.ftt.bit_rate);
}

// The start of the EC the TM `tf` opens (frames::ec_start: its stamp, or
// earlier by its wire time when stamped at its end of frame).
Nanos ec_start(const TimedFrame& tf, const NodeParams& p) { return frames::ec_start(tf.frame, tf.time, p.ftt); }

// Asynchronous message `m`'s slot in the EC the TM at `tm_time` opens (frames::async_slot).
Nanos async_slot(const frames::MessageSet& set, const frames::MessageCodec& m, const NodeParams& p, Nanos tm_time,
                 Nanos last_sent) {
  return frames::async_slot(tm_time, tm_wire_time(p), last_sent, set.ftt(m).min_gap);
}

}  // namespace

// --- FttMaster -----------------------------------------------------------------

FttMaster::FttMaster(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const frames::FttSchedule& schedule,
                     Nanos first_ec)
    : Node(node_name(NodeId::kMaster), bus, std::move(set)), schedule_(schedule), first_ec_(first_ec) {
  const auto longest = std::chrono::ceil<std::chrono::microseconds>(schedule_.longest_sync_window());
  if (longest.count() > std::numeric_limits<std::uint16_t>::max()) {
    throw SetupError("the synchronous window of EC " + std::to_string(schedule_.worst_ec()) + " is " +
                     std::to_string(longest.count()) +
                     " us, more than the trigger message's sync_window_us can say (at most 65535 us); raise the bit "
                     "rate or spread the synchronous messages over more elementary cycles");
  }
  bus.set_filters({});  // hears nothing
  wake_at(first_ec_);
}

void FttMaster::step(Nanos now) {
  const Nanos ec = schedule_.config().elementary_cycle;
  // Behind (real time, after a stall)? Skip to the current EC rather than burst.
  if (now >= first_ec_ + ec * static_cast<std::int64_t>(ec_ + 1)) {
    ec_ = static_cast<std::uint64_t>((now - first_ec_) / ec);
  }
  frames::Tm tm;
  tm.ec_counter = static_cast<std::uint16_t>(ec_ & 0xFFFF);
  tm.sync_bitmap = schedule_.bitmap(ec_);
  // Rounded up: the window announced is never shorter than its frames need
  // (at a bit rate whose bit is not a whole microsecond, e.g. 800 kbit/s).
  tm.sync_window_us = static_cast<std::uint16_t>(
      std::chrono::ceil<std::chrono::microseconds>(schedule_.sync_window(tm.sync_bitmap)).count());
  emit(messages().tm.encode(tm), now);
  ++ec_;
  wake_at(first_ec_ + ec * static_cast<std::int64_t>(ec_));
}

// --- PicBase -------------------------------------------------------------------

PicBase::PicBase(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params, RobotIo& robot)
    : Node(node_name(NodeId::kPicBase), bus, std::move(set)),
      params_(params),
      robot_(robot),
      kinematics_(params.geometry) {
  const auto f = filters_for(messages(), {"TM", "M6_1", "M6_2", "M7"});
  bus.set_filters(f);
}

bool PicBase::watchdog_tripped(Nanos now) const noexcept { return now - last_m6_ > params_.watchdog; }

void PicBase::on_frame(const TimedFrame& tf) {
  const CanFrame& f = tf.frame;
  const frames::MessageSet& s = messages();
  if (is_message(f, s.tm.message())) {
    frames::Tm tm;
    if (!decode(s.tm, f, tm)) return;
    const std::uint32_t mine = (1u << s.ftt(s.m1.message()).index) | (1u << s.ftt(s.m9.message()).index);
    if (const auto start = slot_.on_tm(tm, ec_start(tf, params_), params_.ftt.elementary_cycle, mine)) wake_at(*start);
    const Nanos at = async_slot(s, s.m2.message(), params_, ec_start(tf, params_), last_m2_);
    if (at != kNever) {
      async_at_ = at;
      wake_at(at);
    }
  } else if (is_message(f, s.m6_1.message())) {
    if (decode(s.m6_1, f, m6_1_)) last_m6_ = tf.time;
  } else if (is_message(f, s.m6_2.message())) {
    if (decode(s.m6_2, f, m6_2_)) last_m6_ = tf.time;
  } else if (is_message(f, s.m7.message())) {
    frames::M7 m7;
    if (!decode(s.m7, f, m7)) return;
    if (m7.power() > 0 && robot_.kick(m7.low_kick(), m7.power()) == KickOutcome::kFired) last_kick_ = tf.time;
    grabber_ = m7.grabber_mode;
    robot_.set_grabber(grabber_);
  }
}

void PicBase::send_m1(Nanos now) {
  const bool braking = watchdog_tripped(now);
  std::array<double, 3> target{};
  if (!braking) {
    const kinematics::WheelSpeeds w = kinematics_.inverse({m6_1_.vx, m6_1_.vy, m6_2_.va});
    for (std::size_t n = 0; n < 3; ++n) target[n] = params_.encoder.counts_per_tick(w[n]);
  }
  const double dt = last_m1_ == kLongAgo ? 0.0 : to_seconds(now - last_m1_);
  const double accel = m6_2_.small_adjustment != 0 ? params_.fine_wheel_accel_radps2 : params_.max_wheel_accel_radps2;
  const double max_step = params_.encoder.counts_per_tick(accel) * dt;
  const auto limit = static_cast<double>(params_.max_setpoint);
  frames::M1 m1;
  for (std::size_t n = 0; n < 3; ++n) {
    // Braking is immediate; otherwise the set point follows within the acceleration limit.
    double next = braking ? 0.0 : ramp_[n] + std::clamp(target[n] - ramp_[n], -max_step, max_step);
    next = std::clamp(next, -limit, limit);
    ramp_[n] = next;
    setpoints_[n] = static_cast<int>(std::lround(next));
  }
  m1.setpoint_1 = static_cast<std::int16_t>(setpoints_[0]);
  m1.setpoint_2 = static_cast<std::int16_t>(setpoints_[1]);
  m1.setpoint_3 = static_cast<std::int16_t>(setpoints_[2]);
  m1.enable = braking ? 0 : 1;
  m1.seq = m1_seq_++;
  emit(messages().m1.encode(m1), now);
  last_m1_ = now;
}

void PicBase::step(Nanos now) {
  const frames::MessageSet& s = messages();
  if (async_at_ <= now) {
    const BatteryVolts b = robot_.battery();
    emit(s.m2.encode(frames::M2{b.logic_v, b.power12_v, b.power24_v, robot_.kicker_voltage_v()}), now);
    last_m2_ = now;
    async_at_ = kNever;
  }
  if (slot_.pending(now)) {
    if (slot_.due(s.ftt(s.m1.message()).index)) send_m1(now);
    if (slot_.due(s.ftt(s.m9.message()).index)) {
      frames::M9 m9;
      m9.ball_engaged = robot_.ball_engaged() ? 1 : 0;
      m9.just_kicked = now - last_kick_ <= params_.just_kicked_hold ? 1 : 0;
      m9.kicker_voltage = robot_.kicker_voltage_v();
      m9.grabber = static_cast<std::uint8_t>(grabber_);
      emit(s.m9.encode(m9), now);
    }
    slot_.done();
  }
}

// --- MotorNode -----------------------------------------------------------------

MotorNode::MotorNode(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params,
                     RobotIo& robot, int wheel, Nanos first_tick)
    : Node(node_name(motor_node(wheel)), bus, std::move(set)),
      params_(params),
      robot_(robot),
      wheel_(wheel),
      ticks_(from_seconds(params.encoder.motor_tick_s), first_tick) {
  const auto f = filters_for(messages(), {"TM", "M1"});
  bus.set_filters(f);
  wake_at(ticks_.next());
}

void MotorNode::on_frame(const TimedFrame& tf) {
  const CanFrame& f = tf.frame;
  const frames::MessageSet& s = messages();
  const auto w = static_cast<std::size_t>(wheel_);
  if (is_message(f, s.tm.message())) {
    frames::Tm tm;
    if (!decode(s.tm, f, tm)) return;
    const std::uint32_t mine = 1u << s.ftt(s.m3[w].message()).index;
    if (const auto start = slot_.on_tm(tm, ec_start(tf, params_), params_.ftt.elementary_cycle, mine)) wake_at(*start);
  } else if (is_message(f, s.m1.message())) {
    frames::M1 m1;
    if (!decode(s.m1, f, m1)) return;
    setpoint_ = wheel_ == 0 ? m1.setpoint_1 : wheel_ == 1 ? m1.setpoint_2 : m1.setpoint_3;
    enable_ = m1.enable != 0;
    last_m1_ = tf.time;
  }
}

void MotorNode::step(Nanos now) {
  if (ticks_.due(now)) {
    // The motor tick: the speed loop's target, braked without a fresh M1.
    const bool active = enable_ && now - last_m1_ <= params_.motor_watchdog;
    robot_.set_wheel_speed(wheel_, active ? params_.encoder.wheel_radps(setpoint_) : 0.0);
    ticks_.advance_past(now);
  }
  wake_at(ticks_.next());
  if (slot_.pending(now)) {
    const frames::MessageSet& s = messages();
    const std::int64_t count = robot_.encoder_count(wheel_);
    frames::M3 m3;
    m3.encoder = static_cast<std::int32_t>(static_cast<std::uint32_t>(count & 0xFFFF'FFFF));
    const std::int64_t delta = reported_once_ ? count - last_reported_ : 0;
    m3.delta = static_cast<std::int16_t>(std::clamp<std::int64_t>(delta, -32768, 32767));
    m3.status = static_cast<std::uint8_t>((robot_.wheel_stalled(wheel_) ? frames::M3::kStatusStalled : 0) |
                                          (robot_.over_current(wheel_) ? frames::M3::kStatusOverCurrent : 0));
    m3.seq = seq_++;
    emit(s.m3[static_cast<std::size_t>(wheel_)].encode(m3), now);
    last_reported_ = count;
    reported_once_ = true;
    slot_.done();
  }
}

// --- PicOdom -------------------------------------------------------------------

PicOdom::PicOdom(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params)
    : Node(node_name(NodeId::kPicOdom), bus, std::move(set)), params_(params), kinematics_(params.geometry) {
  const auto f = filters_for(messages(), {"TM", "M3_1", "M3_2", "M3_3", "M5_1", "M5_2"});
  bus.set_filters(f);
}

void PicOdom::integrate() {
  if (have_reference_) {
    kinematics::WheelSpeeds turned{};
    for (std::size_t n = 0; n < 3; ++n) {
      // Encoders wrap at 32 bits: the difference does too.
      const auto d = static_cast<std::int32_t>(static_cast<std::uint32_t>(encoder_[n]) -
                                               static_cast<std::uint32_t>(last_encoder_[n]));
      turned[n] = params_.encoder.wheel_angle_rad(d);
    }
    // Wheel angles turned -> displacement (a twist over one unit of time).
    pose_ = kinematics::integrate(pose_, kinematics_.forward(turned), 1.0);
  }
  last_encoder_ = encoder_;
  have_reference_ = true;
  seen_ = {};
}

void PicOdom::on_frame(const TimedFrame& tf) {
  const CanFrame& f = tf.frame;
  const frames::MessageSet& s = messages();
  if (is_message(f, s.tm.message())) {
    frames::Tm tm;
    if (!decode(s.tm, f, tm)) return;
    const std::uint32_t mine = (1u << s.ftt(s.m4_1.message()).index) | (1u << s.ftt(s.m4_2.message()).index);
    if (const auto start = slot_.on_tm(tm, ec_start(tf, params_), params_.ftt.elementary_cycle, mine)) wake_at(*start);
    return;
  }
  for (std::size_t n = 0; n < 3; ++n) {
    if (is_message(f, s.m3[n].message())) {
      frames::M3 m3;
      if (!decode(s.m3[n], f, m3)) return;
      encoder_[n] = m3.encoder;
      seen_[n] = true;
      if (seen_[0] && seen_[1] && seen_[2]) integrate();
      return;
    }
  }
  if (is_message(f, s.m5_1.message())) {
    frames::M5_1 m5;
    if (decode(s.m5_1, f, m5)) m5_1_ = m5;
  } else if (is_message(f, s.m5_2.message())) {
    frames::M5_2 m5;
    if (!decode(s.m5_2, f, m5)) return;
    if (m5.command == frames::M5_2::kReset) {
      pose_ = kinematics::Pose{};
    } else {
      pose_.heading_rad = kinematics::wrap_pi(m5.theta);
      if (m5_1_) {
        pose_.x_m = m5_1_->x;
        pose_.y_m = m5_1_->y;
      }
    }
    m5_1_.reset();
  }
}

void PicOdom::step(Nanos now) {
  if (!slot_.pending(now)) return;
  const frames::MessageSet& s = messages();
  if (slot_.due(s.ftt(s.m4_1.message()).index)) emit(s.m4_1.encode(frames::M4_1{pose_.x_m, pose_.y_m}), now);
  if (slot_.due(s.ftt(s.m4_2.message()).index)) {
    emit(s.m4_2.encode(frames::M4_2{kinematics::wrap_pi(pose_.heading_rad), seq_++}), now);
  }
  slot_.done();
}

// --- CompassNode ---------------------------------------------------------------

CompassNode::CompassNode(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params,
                         RobotIo& robot)
    : Node(node_name(NodeId::kCompass), bus, std::move(set)), params_(params), robot_(robot) {
  const auto f = filters_for(messages(), {"TM"});
  bus.set_filters(f);
}

void CompassNode::on_frame(const TimedFrame& tf) {
  const frames::MessageSet& s = messages();
  frames::Tm tm;
  if (!is_message(tf.frame, s.tm.message()) || !decode(s.tm, tf.frame, tm)) return;
  if (const auto start =
          slot_.on_tm(tm, ec_start(tf, params_), params_.ftt.elementary_cycle, 1u << s.ftt(s.m8.message()).index)) {
    wake_at(*start);
  }
}

void CompassNode::step(Nanos now) {
  if (!slot_.pending(now)) return;
  double heading = std::round(robot_.compass_heading_deg() * 100.0) / 100.0;
  if (heading >= 360.0) heading -= 360.0;
  // raw: the heading in tenths of a degree, centred on zero (what an
  // uncalibrated sensor word looks like; canhil defines it, see docs/nodes.md).
  const auto raw = static_cast<std::int16_t>(std::lround(heading * 10.0) - 1800);
  emit(messages().m8.encode(frames::M8{heading, raw}), now);
  slot_.done();
}

// --- SystemMonitor -------------------------------------------------------------

SystemMonitor::SystemMonitor(Endpoint& bus, std::shared_ptr<const frames::MessageSet> set, const NodeParams& params,
                             std::function<std::uint64_t()> bad_frames, std::function<std::uint8_t(Nanos)> state,
                             Endpoint* watch)
    : Node(node_name(NodeId::kSysMon), bus, std::move(set)),
      params_(params),
      watch_(watch),
      bad_frames_(std::move(bad_frames)),
      state_(std::move(state)) {
  last_seen_.fill(kLongAgo);
  static constexpr std::array<const char*, 6> kWatched = {"Pic_base", "Motor1",   "Motor2",
                                                          "Motor3",   "Pic_odom", "Compass"};
  for (const frames::MessageCodec& m : messages().codec().messages()) {
    const auto at = std::find(kWatched.begin(), kWatched.end(), m.def().transmitter);
    watched_.push_back(at == kWatched.end() ? kNotWatched : static_cast<std::uint8_t>(at - kWatched.begin()));
  }
  const Filter all[] = {Filter::all()};
  if (watch_ != nullptr) {
    const Filter tm[] = {Filter::exact(messages().tm.message().id())};
    bus.set_filters(tm);
    watch_->set_filters(all);
  } else {
    bus.set_filters(all);  // watches the whole bus
  }
}

std::size_t SystemMonitor::poll_more(std::size_t max_frames) {
  if (watch_ == nullptr) return 0;
  std::size_t n = 0;
  while (n < max_frames) {
    auto f = watch_->receive();
    if (!f) break;
    ++n;
    if (enabled()) observe(*f);
  }
  return n;
}

std::uint8_t SystemMonitor::alive(Nanos now) const noexcept {
  std::uint8_t bits = 0;
  for (std::size_t i = 0; i < last_seen_.size(); ++i) {
    if (now - last_seen_[i] <= params_.alive_timeout) bits |= static_cast<std::uint8_t>(1u << i);
  }
  return bits;
}

void SystemMonitor::observe(const TimedFrame& tf) {
  const CanFrame& f = tf.frame;
  if (f.kind != frames::FrameKind::kData) return;
  const frames::MessageCodec* m = messages().codec().find(f.id, f.extended);
  if (m == nullptr) {
    count_unknown();
    return;
  }
  const std::uint8_t from = watched_[static_cast<std::size_t>(m - messages().codec().messages().data())];
  if (from != kNotWatched) last_seen_[from] = tf.time;  // a watched node is alive
}

void SystemMonitor::on_frame(const TimedFrame& tf) {
  const CanFrame& f = tf.frame;
  if (watch_ == nullptr) observe(tf);
  if (is_message(f, messages().tm.message())) {
    const Nanos at = async_slot(messages(), messages().m10.message(), params_, ec_start(tf, params_), last_m10_);
    if (at != kNever) {
      async_at_ = at;
      wake_at(at);
    }
  }
}

void SystemMonitor::step(Nanos now) {
  if (async_at_ > now) return;
  const std::uint64_t bad = bad_frames_() + counters().bad_frames();
  frames::M10 m10;
  m10.alive = alive(now);
  m10.errors = static_cast<std::uint16_t>(std::min<std::uint64_t>(bad, 0xFFFF));
  m10.node_state = state_(now);
  emit(messages().m10.encode(m10), now);
  last_m10_ = now;
  async_at_ = kNever;
}

}  // namespace canhil::can_nodes
