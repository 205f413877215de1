#include "canhil/laptop/hwcomm.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/rtdb.h"
#include "rtdb_user.h"

namespace canhil::laptop {
namespace {

bool is(const frames::CanFrame& f, const frames::MessageCodec& m) {
  return f.kind == frames::FrameKind::kData && !f.extended && f.id == m.id();
}

unsigned short sat16(double v) { return static_cast<unsigned short>(std::clamp(std::lround(v), 0L, 65535L)); }

}  // namespace

HwComm::HwComm(std::shared_ptr<const frames::MessageSet> set, Nanos ec, Send send, Clock clock, int agent)
    : set_(std::move(set)), ec_(ec), send_(std::move(send)), clock_(std::move(clock)), agent_(agent) {
  stats_.received.assign(set_->codec().messages().size(), 0);
  stats_.sent.assign(set_->codec().messages().size(), 0);
}

std::size_t HwComm::index_of(const frames::MessageCodec& m) const noexcept {
  return static_cast<std::size_t>(&m - set_->codec().messages().data());
}

std::uint64_t HwComm::received(std::string_view name) const noexcept {
  const frames::MessageCodec* m = set_->codec().find(name);
  return m == nullptr ? 0 : stats_.received[index_of(*m)];
}

std::uint64_t HwComm::sent(std::string_view name) const noexcept {
  const frames::MessageCodec* m = set_->codec().find(name);
  return m == nullptr ? 0 : stats_.sent[index_of(*m)];
}

int HwComm::get(int id, void* value) const {
  return agent_ < 0 ? DB_get(Whoami(), id, value) : DB_get_from(agent_, agent_, id, value);
}

void HwComm::put(int id, void* value) const {
  if (agent_ < 0) {
    DB_put(id, value);
  } else {
    DB_put_in(agent_, agent_, id, value, 0);
  }
}

void HwComm::send(const frames::CanFrame& f, const frames::MessageCodec& message) {
  if (send_(f)) {
    ++stats_.sent[index_of(message)];
  } else {
    ++stats_.send_failed;
  }
}

void HwComm::latency(Nanos rx_time) {
  if (stats_.latencies.size() < kMaxLatencySamples) stats_.latencies.push_back(clock_() - rx_time);
}

template <class T>
static bool usable(const frames::TypedCodec<T>& codec, const frames::CanFrame& f, T& out, HwCommStats& s) {
  const frames::DecodeResult r = codec.decode(f, out);
  if (r.status == frames::DecodeStatus::kWrongLength) {
    ++s.wrong_length;
    return false;
  }
  if (r.status != frames::DecodeStatus::kOk) return false;
  if (r.out_of_range != 0) {
    ++s.out_of_range;
    return false;
  }
  return true;
}

void HwComm::on_frame(const frames::CanFrame& f, Nanos rx) {
  if (f.kind != frames::FrameKind::kData) return;
  const frames::MessageCodec* m = set_->codec().find(f.id, f.extended);
  if (m == nullptr) {
    ++stats_.unknown_id;
    return;
  }
  ++stats_.received[index_of(*m)];
  const frames::MessageSet& s = *set_;
  if (is(f, s.tm.message())) {
    frames::Tm tm;
    if (usable(s.tm, f, tm, stats_)) on_tm(tm, rx);
  } else if (is(f, s.m4_1.message())) {
    have_m4_1_ = usable(s.m4_1, f, m4_1_, stats_);
  } else if (is(f, s.m4_2.message())) {
    frames::M4_2 m4;
    if (!usable(s.m4_2, f, m4, stats_) || !have_m4_1_) return;
    CMD_Pos p;
    p.px = static_cast<float>(m4_1_.x);
    p.py = static_cast<float>(m4_1_.y);
    p.pa = static_cast<float>(m4.theta);
    p.dx = have_pose_ ? p.px - last_px_ : 0.0f;
    p.dy = have_pose_ ? p.py - last_py_ : 0.0f;
    p.da = have_pose_ ? static_cast<float>(std::remainder(p.pa - last_pa_, 2.0 * 3.14159265358979)) : 0.0f;
    last_px_ = p.px;
    last_py_ = p.py;
    last_pa_ = p.pa;
    have_pose_ = true;
    have_m4_1_ = false;
    put(CMD_POS, &p);
    latency(rx);
  } else if (is(f, s.m2.message())) {
    frames::M2 m2;
    if (!usable(s.m2, f, m2, stats_)) return;
    CMD_Info info;
    get(CMD_INFO, &info);
    info.Voltage_logic = sat16(m2.v_logic * 100);
    info.Voltage_power12 = sat16(m2.v_power12 * 100);
    info.Voltage_power24 = sat16(m2.v_power24 * 100);
    put(CMD_INFO, &info);
    latency(rx);
  } else if (is(f, s.m9.message())) {
    frames::M9 m9;
    if (!usable(s.m9, f, m9, stats_)) return;
    CMD_Info info;
    get(CMD_INFO, &info);
    info.justKicked = m9.just_kicked != 0;
    info.Kicker_voltage = sat16(m9.kicker_voltage * 100);
    put(CMD_INFO, &info);
    CMD_Grabber_Info g{m9.ball_engaged, m9.grabber};
    put(CMD_GRABBER_INFO, &g);
    latency(rx);
  } else if (is(f, s.m8.message())) {
    frames::M8 m8;
    if (!usable(s.m8, f, m8, stats_)) return;
    CMD_Imu imu;
    imu.compass = static_cast<int>(std::lround(m8.heading)) % 360;
    imu.yaw = static_cast<int>(std::lround(m8.heading * 100));
    imu.rawYaw = m8.raw;
    put(CMD_IMU, &imu);
    latency(rx);
  } else if (is(f, s.m10.message())) {
    if (usable(s.m10, f, m10_, stats_)) {
      write_hwerrors();
      latency(rx);
    }
  }
}

void HwComm::write_hwerrors() {
  CMD_HWerrors e;
  std::memset(&e, 0, sizeof e);
  e.error_count[0][0] = m10_.errors;
  e.error_count[0][1] = m10_.alive;
  e.error_count[0][2] = m10_.node_state;
  const std::uint64_t own[] = {stats_.wrong_length, stats_.out_of_range, stats_.unknown_id, stats_.missed_tms,
                               stats_.send_failed};
  for (std::size_t i = 0; i < std::size(own); ++i) {
    e.error_count[1][i] = static_cast<unsigned short>(std::min<std::uint64_t>(own[i], 65535));
  }
  put(CMD_HWERRORS, &e);
}

void HwComm::on_tm(const frames::Tm& tm, Nanos rx) {
  if (have_tm_) {
    const auto gap = static_cast<std::uint16_t>(tm.ec_counter - last_ec_);
    if (gap > 1) stats_.missed_tms += gap - 1u;
  }
  have_tm_ = true;
  last_ec_ = tm.ec_counter;
  const frames::MessageSet& s = *set_;
  const std::uint32_t m6 = (1u << s.ftt(s.m6_1.message()).index) | (1u << s.ftt(s.m6_2.message()).index);
  if (const auto start = m6_slot_.on_tm(tm, rx, ec_, m6)) m6_at_ = *start;
  // The asynchronous window opens now: kicker and grabber, pose.
  const Nanos now = rx;
  CMD_Kicker kick;
  CMD_Grabber grab;
  get(CMD_KICKER, &kick);
  get(CMD_GRABBER, &grab);
  const bool kick_wanted = (kick.power & 0x7F) != 0;
  const bool grabber_changed = grab.mode != last_grabber_;
  if ((kick_wanted || grabber_changed) && now - last_m7_ >= s.ftt(s.m7.message()).min_gap) {
    frames::M7 m7;
    m7.kick = kick.power;
    m7.grabber_mode = std::min<std::uint8_t>(grab.mode, 100);
    m7.eng_lvl_high = kick.engLvlHigh;
    m7.eng_lvl_low = kick.engLvlLow;
    send(s.m7.encode(m7), s.m7.message());
    last_m7_ = now;
    last_grabber_ = grab.mode;
    if (kick_wanted) {
      ++stats_.kicks_sent;
      kick.power = 0;  // sent once: the agent asks again for another kick
      put(CMD_KICKER, &kick);
    }
  }
  CMD_SetPose pose;
  get(CMD_SETPOSE, &pose);
  if (pose.pending != 0 && now - last_m5_ >= s.ftt(s.m5_1.message()).min_gap) {
    send(s.m5_1.encode(frames::M5_1{pose.px, pose.py}), s.m5_1.message());
    send(s.m5_2.encode(frames::M5_2{pose.pa, pose.command}), s.m5_2.message());
    last_m5_ = now;
    pose.pending = 0;
    put(CMD_SETPOSE, &pose);
  }
}

void HwComm::on_time(Nanos now) {
  if (now < m6_at_) return;
  m6_at_ = kNever;
  m6_slot_.done();
  CMD_Vel v;
  get(CMD_VEL, &v);
  const frames::MessageSet& s = *set_;
  send(s.m6_1.encode(frames::M6_1{v.vx, v.vy}), s.m6_1.message());
  send(s.m6_2.encode(frames::M6_2{v.va, static_cast<std::uint8_t>(v.smallAdjustment ? 1 : 0), m6_seq_++}),
       s.m6_2.message());
}

std::string HwComm::summary() const {
  std::ostringstream os;
  // By name, as before: the names are looked up here, once, not per frame.
  const auto by_name = [this](const std::vector<std::uint64_t>& counts) {
    std::map<std::string_view, std::uint64_t> out;
    const auto messages = set_->codec().messages();
    for (std::size_t i = 0; i < counts.size(); ++i) {
      if (counts[i] != 0) out[messages[i].name()] = counts[i];
    }
    return out;
  };
  os << "  received:";
  for (const auto& [name, n] : by_name(stats_.received)) os << ' ' << name << ' ' << n;
  os << "\n  sent:";
  for (const auto& [name, n] : by_name(stats_.sent)) os << ' ' << name << ' ' << n;
  os << "\n  kicks sent " << stats_.kicks_sent << ", missed TMs " << stats_.missed_tms << ", wrong length "
     << stats_.wrong_length << ", out of range " << stats_.out_of_range << ", unknown ids " << stats_.unknown_id
     << ", send failures " << stats_.send_failed << "\n";
  if (!stats_.latencies.empty()) {
    std::vector<Nanos> l = stats_.latencies;
    std::sort(l.begin(), l.end());
    auto us = [](Nanos t) { return std::chrono::duration<double, std::micro>(t).count(); };
    auto pct = [&](double p) {
      return l[std::min(l.size() - 1, static_cast<std::size_t>(p * static_cast<double>(l.size())))];
    };
    os << "  latency receive timestamp -> RTDB write over " << l.size() << " updates: p50 " << us(pct(0.5))
       << " us, p99 " << us(pct(0.99)) << " us, max " << us(l.back()) << " us\n";
  }
  return os.str();
}

}  // namespace canhil::laptop
