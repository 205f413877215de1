#include "canhil/laptop/hwcomm.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/ftt.hpp"
#include "canhil/frames/wire.hpp"
#include "rtdb_item.hpp"

namespace canhil::laptop {

struct HwComm::Items {
  Items(rtdb::Database& database, int agent) : db(database), space(agent) {}
  rtdb::Database& db;
  int space;
  Item pos, info, grabber_info, imu, hwerrors, vel, last_vel, kicker, grabber, setpose;
  rtdb::Quantity x, y, heading, dx, dy, dheading;
  rtdb::DeltasFrame deltas = rtdb::DeltasFrame::kOdometry;
  rtdb::Quantity v_logic, v_power12, v_power24, v_kicker, just_kicked;
  rtdb::Quantity ball_engaged, grabber_state, compass, compass_raw;
  rtdb::Quantity vx, vy, va, small, last_vx, last_vy, last_va, last_small;
  rtdb::Quantity kick, eng_high, eng_low, grab;
  rtdb::Quantity set_x, set_y, set_heading, set_command, set_pending;

  // Reads the item as the agent last wrote it.
  void get(Item& i) { read_item(db, space, space, i); }
  void put(const Item& i) { write_item(db, space, i); }
};

HwComm::HwComm(std::shared_ptr<const frames::MessageSet> set, Nanos ec, Send send, Clock clock, rtdb::Database& db,
               const rtdb::Layout& layout, int space)
    : set_(std::move(set)), ec_(ec), send_(std::move(send)), clock_(std::move(clock)) {
  ftt_.elementary_cycle = ec;
  stats_.received.assign(set_->codec().messages().size(), 0);
  stats_.sent.assign(set_->codec().messages().size(), 0);
  set_bit_rate(frames::FttConfig{}.bit_rate);
  items_ = std::make_unique<Items>(db, space);
  Items& i = *items_;
  i.pos = resolve(db, layout, space, "CMD_POS", {"x", "y", "heading"}, true);
  i.x = i.pos.q("x");
  i.y = i.pos.q("y");
  i.heading = i.pos.q("heading");
  i.dx = i.pos.q("dx");
  i.dy = i.pos.q("dy");
  i.dheading = i.pos.q("dheading");
  i.deltas = i.pos.buf->layout().deltas_frame();
  i.info = resolve(db, layout, space, "CMD_INFO", {"v_logic", "v_power12", "v_power24", "v_kicker"}, true);
  i.v_logic = i.info.q("v_logic");
  i.v_power12 = i.info.q("v_power12");
  i.v_power24 = i.info.q("v_power24");
  i.v_kicker = i.info.q("v_kicker");
  i.just_kicked = i.info.q("just_kicked");
  i.grabber_info = resolve(db, layout, space, "CMD_GRABBER_INFO", {"ball_engaged"}, true);
  i.ball_engaged = i.grabber_info.q("ball_engaged");
  i.grabber_state = i.grabber_info.q("grabber");
  i.imu = resolve(db, layout, space, "CMD_IMU", {"heading"}, true);
  i.compass = i.imu.q("heading");
  i.compass_raw = i.imu.q("raw");
  i.hwerrors = resolve(db, layout, space, "CMD_HWERRORS", {}, false);
  i.vel = resolve(db, layout, space, "CMD_VEL", {"vx", "vy", "va"}, true);
  i.vx = i.vel.q("vx");
  i.vy = i.vel.q("vy");
  i.va = i.vel.q("va");
  i.small = i.vel.q("small_adjustment");
  i.last_vel = resolve(db, layout, space, "LAST_CMD_VEL", {"vx", "vy", "va"}, false);
  if (i.last_vel) {
    i.last_vx = i.last_vel.q("vx");
    i.last_vy = i.last_vel.q("vy");
    i.last_va = i.last_vel.q("va");
    i.last_small = i.last_vel.q("small_adjustment");
  }
  i.kicker = resolve(db, layout, space, "CMD_KICKER", {"kick"}, true);
  i.kick = i.kicker.q("kick");
  i.eng_high = i.kicker.q("eng_level_high");
  i.eng_low = i.kicker.q("eng_level_low");
  i.grabber = resolve(db, layout, space, "CMD_GRABBER", {"grabber"}, true);
  i.grab = i.grabber.q("grabber");
  i.setpose = resolve(db, layout, space, "CMD_SETPOSE", {"x", "y", "heading", "command", "pending"}, false);
  if (i.setpose) {
    i.set_x = i.setpose.q("x");
    i.set_y = i.setpose.q("y");
    i.set_heading = i.setpose.q("heading");
    i.set_command = i.setpose.q("command");
    i.set_pending = i.setpose.q("pending");
  }
}

HwComm::~HwComm() = default;

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

void HwComm::on_error_frame(const frames::CanFrame& f) {
  ++stats_.error_frames;
  const std::uint32_t classes = f.id;
  if ((classes & (frames::kErrorClassProtocol | frames::kErrorClassBusError | frames::kErrorClassNoAck)) != 0) {
    ++stats_.bus_errors;
  }
  if ((classes & frames::kErrorClassController) != 0) {
    const std::uint8_t s = f.data[1];
    if ((s & (frames::kControllerTxPassive | frames::kControllerRxPassive)) != 0) {
      stats_.controller = ControllerState::kErrorPassive;
    } else if ((s & (frames::kControllerTxWarning | frames::kControllerRxWarning)) != 0) {
      stats_.controller = ControllerState::kErrorWarning;
    } else if ((s & frames::kControllerActive) != 0) {
      stats_.controller = ControllerState::kErrorActive;
    }
  }
  if ((classes & frames::kErrorClassBusOff) != 0) {
    ++stats_.bus_offs;
    stats_.controller = ControllerState::kBusOff;
  }
  if ((classes & frames::kErrorClassRestarted) != 0) {
    // Back on the bus: what it queued goes out, and the next TM sets its slots again.
    ++stats_.restarts;
    stats_.controller = ControllerState::kErrorActive;
  }
  if ((classes & frames::kErrorClassCounters) != 0) {
    stats_.tec = f.data[6];
    stats_.rec = f.data[7];
  }
}

void HwComm::on_frame(const frames::CanFrame& f, Nanos rx) {
  if (f.kind == frames::FrameKind::kError) {
    on_error_frame(f);
    return;
  }
  if (f.kind != frames::FrameKind::kData) return;
  const frames::MessageCodec* m = set_->codec().find(f.id, f.extended);
  if (m == nullptr) {
    ++stats_.unknown_id;
    return;
  }
  ++stats_.received[index_of(*m)];
  const frames::MessageSet& s = *set_;
  if (frames::is_message(f, s.tm.message())) {
    frames::Tm tm;
    if (usable(s.tm, f, tm, stats_)) on_tm(tm, frames::ec_start(f, rx, ftt_));
  } else if (frames::is_message(f, s.m4_1.message())) {
    have_m4_1_ = usable(s.m4_1, f, m4_1_, stats_);
  } else if (frames::is_message(f, s.m4_2.message())) {
    frames::M4_2 m4;
    if (!usable(s.m4_2, f, m4, stats_) || !have_m4_1_) return;
    on_pose(m4);
    latency(rx);
  } else if (frames::is_message(f, s.m2.message())) {
    frames::M2 m2;
    if (!usable(s.m2, f, m2, stats_)) return;
    Items& i = *items_;
    i.get(i.info);
    i.info.buf->set(i.v_logic, m2.v_logic);
    i.info.buf->set(i.v_power12, m2.v_power12);
    i.info.buf->set(i.v_power24, m2.v_power24);
    i.put(i.info);
    latency(rx);
  } else if (frames::is_message(f, s.m9.message())) {
    frames::M9 m9;
    if (!usable(s.m9, f, m9, stats_)) return;
    Items& i = *items_;
    i.get(i.info);
    i.info.buf->set(i.just_kicked, m9.just_kicked != 0 ? 1.0 : 0.0);
    i.info.buf->set(i.v_kicker, m9.kicker_voltage);
    i.put(i.info);
    i.grabber_info.buf->clear();
    i.grabber_info.buf->set(i.ball_engaged, m9.ball_engaged != 0 ? 1.0 : 0.0);
    i.grabber_info.buf->set(i.grabber_state, m9.grabber / 100.0);  // M9 carries 0..100
    i.put(i.grabber_info);
    latency(rx);
  } else if (frames::is_message(f, s.m8.message())) {
    frames::M8 m8;
    if (!usable(s.m8, f, m8, stats_)) return;
    Items& i = *items_;
    i.imu.buf->clear();
    i.imu.buf->set(i.compass, m8.heading);  // degrees clockwise from north, as the node reports it
    i.imu.buf->set(i.compass_raw, m8.raw);
    i.put(i.imu);
    latency(rx);
  } else if (frames::is_message(f, s.m10.message())) {
    if (usable(s.m10, f, m10_, stats_)) {
      write_hwerrors();
      latency(rx);
    }
  }
}

void HwComm::on_pose(const frames::M4_2& m4) {
  Items& i = *items_;
  rtdb::ItemBuffer& b = *i.pos.buf;
  // As the team's struct stores them (a float pose stays a float pose), so
  // that the deltas add up to the pose the agent reads.
  b.clear();
  b.set(i.x, m4_1_.x);
  b.set(i.y, m4_1_.y);
  b.set(i.heading, m4.theta);
  const double x = b.get(i.x), y = b.get(i.y), heading = b.get(i.heading);
  double dx = 0, dy = 0, dheading = 0;
  if (have_pose_) {
    dx = x - last_x_;
    dy = y - last_y_;
    dheading = std::remainder(heading - last_heading_, 2.0 * M_PI);
    if (i.deltas == rtdb::DeltasFrame::kRobot) {
      const double c = std::cos(heading), s = std::sin(heading);
      const double rx = c * dx + s * dy;
      dy = -s * dx + c * dy;
      dx = rx;
    }
  }
  b.set(i.dx, dx);
  b.set(i.dy, dy);
  b.set(i.dheading, dheading);
  last_x_ = x;
  last_y_ = y;
  last_heading_ = heading;
  have_pose_ = true;
  have_m4_1_ = false;
  i.put(i.pos);
}

void HwComm::write_hwerrors() {
  Items& i = *items_;
  if (!i.hwerrors) return;
  rtdb::ItemBuffer& b = *i.hwerrors.buf;
  b.clear();
  b.set(b.quantity("bad_frames"), m10_.errors);
  b.set(b.quantity("alive"), m10_.alive);
  b.set(b.quantity("node_state"), m10_.node_state);
  b.set(b.quantity("wrong_length"), static_cast<double>(stats_.wrong_length));
  b.set(b.quantity("out_of_range"), static_cast<double>(stats_.out_of_range));
  b.set(b.quantity("unknown_id"), static_cast<double>(stats_.unknown_id));
  b.set(b.quantity("missed_tms"), static_cast<double>(stats_.missed_tms));
  b.set(b.quantity("send_failed"), static_cast<double>(stats_.send_failed));
  i.put(i.hwerrors);
}

void HwComm::on_tm(const frames::Tm& tm, Nanos ec_start) {
  if (have_tm_) {
    const auto gap = static_cast<std::uint16_t>(tm.ec_counter - last_ec_);
    if (gap > 1) stats_.missed_tms += gap - 1u;
  }
  have_tm_ = true;
  last_ec_ = tm.ec_counter;
  const frames::MessageSet& s = *set_;
  const std::uint32_t m6 = (1u << s.ftt(s.m6_1.message()).index) | (1u << s.ftt(s.m6_2.message()).index);
  if (const auto window = m6_slot_.on_tm(tm, ec_start, ec_, m6)) m6_at_ = *window;
  // Kicker and grabber, pose: when the TM has left the wire.
  async_at_ = frames::async_slot(ec_start, tm_wire_, kLongAgo, Nanos{0});
}

void HwComm::set_bit_rate(std::uint32_t bit_rate) {
  if (bit_rate == 0) throw SetupError("the bit rate must be positive");
  ftt_.bit_rate = bit_rate;
  const frames::MessageDef& tm = set_->tm.message().def();
  tm_wire_ = frames::bits_to_time(frames::worst_case_frame_bits(tm.length, tm.extended), bit_rate);
}

void HwComm::send_sporadic(Nanos now) {
  const frames::MessageSet& s = *set_;
  Items& i = *items_;
  i.get(i.kicker);
  i.get(i.grabber);
  const auto kick = static_cast<std::uint8_t>(std::clamp(i.kicker.buf->get(i.kick), 0.0, 255.0));
  const double grab = std::clamp(i.grabber.buf->get(i.grab), 0.0, 1.0);
  const bool kick_wanted = (kick & 0x7F) != 0;
  const bool grabber_changed = grab != last_grabber_;
  if ((kick_wanted || grabber_changed) && now - last_m7_ >= s.ftt(s.m7.message()).min_gap) {
    frames::M7 m7;
    m7.kick = kick;
    m7.grabber_mode = static_cast<std::uint8_t>(std::lround(grab * 100));
    m7.eng_lvl_high = static_cast<std::uint8_t>(std::clamp(i.kicker.buf->get(i.eng_high), 0.0, 255.0));
    m7.eng_lvl_low = static_cast<std::uint8_t>(std::clamp(i.kicker.buf->get(i.eng_low), 0.0, 255.0));
    send(s.m7.encode(m7), s.m7.message());
    last_m7_ = now;
    last_grabber_ = grab;
    if (kick_wanted) {
      ++stats_.kicks_sent;
      i.kicker.buf->set(i.kick, 0.0);  // sent once: the agent asks again for another kick
      i.put(i.kicker);
    }
  }
  if (!i.setpose) return;
  i.get(i.setpose);
  rtdb::ItemBuffer& pose = *i.setpose.buf;
  if (pose.get(i.set_pending) != 0 && now - last_m5_ >= s.ftt(s.m5_1.message()).min_gap) {
    send(s.m5_1.encode(frames::M5_1{pose.get(i.set_x), pose.get(i.set_y)}), s.m5_1.message());
    send(s.m5_2.encode(frames::M5_2{pose.get(i.set_heading), static_cast<std::uint8_t>(pose.get(i.set_command))}),
         s.m5_2.message());
    last_m5_ = now;
    pose.set(i.set_pending, 0.0);
    i.put(i.setpose);
  }
}

void HwComm::on_time(Nanos now) {
  if (now >= async_at_) {
    const Nanos slot = async_at_;
    async_at_ = kNever;
    send_sporadic(slot);
  }
  if (now < m6_at_) return;
  m6_at_ = kNever;
  m6_slot_.done();
  Items& i = *items_;
  i.get(i.vel);
  const rtdb::ItemBuffer& v = *i.vel.buf;
  const double vx = v.get(i.vx), vy = v.get(i.vy), va = v.get(i.va), small = v.get(i.small);
  const frames::MessageSet& s = *set_;
  send(s.m6_1.encode(frames::M6_1{vx, vy}), s.m6_1.message());
  send(s.m6_2.encode(frames::M6_2{va, static_cast<std::uint8_t>(small != 0 ? 1 : 0), m6_seq_++}), s.m6_2.message());
  if (i.last_vel) {  // the team's agent reads back what was sent
    rtdb::ItemBuffer& last = *i.last_vel.buf;
    last.clear();
    last.set(i.last_vx, vx);
    last.set(i.last_vy, vy);
    last.set(i.last_va, va);
    last.set(i.last_small, small);
    i.put(i.last_vel);
  }
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
  if (stats_.error_frames > 0) {
    os << "  bus: " << stats_.error_frames << " error frames (" << stats_.bus_errors << " bus errors, "
       << stats_.bus_offs << " bus-off, " << stats_.restarts << " restarts), controller "
       << frames::state_name(stats_.controller) << ", TEC " << int{stats_.tec} << " REC " << int{stats_.rec} << "\n";
  }
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
