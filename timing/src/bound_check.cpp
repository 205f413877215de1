#include "canhil/timing/bound_check.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "canhil/frames/describe.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "units.hpp"

namespace canhil::timing {
namespace {

using frames::FttKind;

std::uint64_t key(std::uint32_t id, bool extended) noexcept { return (std::uint64_t{extended} << 32) | id; }

using units::us;

}  // namespace

const char* bounded_name(Bounded q) noexcept {
  switch (q) {
    case Bounded::kInterval:
      return "interval";
    case Bounded::kEndInWindow:
      return "end in window";
    case Bounded::kAfterOpen:
      return "after window opened";
  }
  return "?";
}

BoundChecker::BoundChecker(const BusAnalysis& a, std::shared_ptr<const frames::MessageSet> set, Nanos slack)
    : set_(std::move(set)), slack_(slack), ec_(a.config.ftt.elementary_cycle), ftt_(a.config.ftt) {
  if (!a.ftt) {
    for (const ResponseBound& m : a.native.messages) {
      Watch& w = watch_[key(m.id, m.extended)];
      const auto f = std::find_if(a.frames.begin(), a.frames.end(),
                                  [&](const FrameRow& r) { return r.id == m.id && r.extended == m.extended; });
      w.kind = f->kind;
      if (f->kind == FttKind::kSync && m.worst_response != kNever) {
        const Nanos spread = m.worst_response - f->time.best;
        w.interval = observe(m.name, Bounded::kInterval, m.period - spread, m.period + spread);
      }
    }
    return;
  }
  for (const FrameRow& f : a.frames) {
    if (f.kind != FttKind::kTrigger) continue;
    tm_wire_ = f.time.worst;
    Watch& w = watch_[key(f.id, f.extended)];
    w.kind = FttKind::kTrigger;
    w.interval = observe(f.name, Bounded::kInterval, ec_, ec_);
  }
  for (const SyncBound& m : a.sync.messages) {
    Watch& w = watch_[key(m.id, false)];
    w.kind = FttKind::kSync;
    w.in_window = observe(m.name, Bounded::kEndInWindow, Nanos{0}, m.worst_offset);
    w.interval = observe(m.name, Bounded::kInterval, m.interval_low, m.interval_high);
  }
  for (const AsyncBound& m : a.async.messages) {
    Watch& w = watch_[key(m.id, m.extended)];
    w.kind = FttKind::kAsync;
    if (m.from_window != kNever) w.in_window = observe(m.name, Bounded::kAfterOpen, Nanos{0}, m.from_window);
  }
}

std::size_t BoundChecker::observe(const std::string& name, Bounded q, Nanos low, Nanos high) {
  Observation o;
  o.message = name;
  o.quantity = q;
  o.low = low;
  o.high = high;
  report_.observations.push_back(o);
  return report_.observations.size() - 1;
}

void BoundChecker::note(std::size_t i, Nanos value, Nanos at) {
  Observation& o = report_.observations[i];
  ++o.count;
  o.least = std::min(o.least, value);
  if (value > o.most || o.count == 1) {
    o.most = value;
    o.most_at = at;
  }
  if (value >= o.low - slack_ && value <= o.high + slack_) return;
  ++o.outside;
  if (report_.violations.size() < BoundReport::kMostListed)
    report_.violations.push_back({at, o.message, o.quantity, value, o.low, o.high});
  ++report_.violation_count;
}

void BoundChecker::add(const frames::TimedFrame& tf) {
  const frames::CanFrame& f = tf.frame;
  if (f.kind != frames::FrameKind::kData) return;
  ++report_.frames;
  const auto it = watch_.find(key(f.id, f.extended));
  if (it == watch_.end()) return;
  Watch& w = it->second;
  const Nanos t = tf.time;
  // The TM's interval is its EC's (stamped at its end of frame, a TM's own
  // stuffing would move it by a few bits; the master keeps the EC's start).
  const Nanos at = w.kind == FttKind::kTrigger ? frames::ec_start(f, t, ftt_) : t;
  if (w.interval != ~std::size_t{0} && w.last != kNever) note(w.interval, at - w.last, t);
  w.last = at;
  if (w.kind == FttKind::kTrigger) {
    frames::Tm tm;
    if (set_ != nullptr && set_->tm.decode(f, tm).status == frames::DecodeStatus::kOk) {
      have_tm_ = true;
      const Nanos start = at;  // the EC's start: the TM's stamp, or before it
      window_start_ = frames::sync_window_start(tm, start, ec_);
      async_open_ = start + tm_wire_;
    }
    return;
  }
  if (!have_tm_ || w.in_window == ~std::size_t{0}) return;
  note(w.in_window, t - (w.kind == FttKind::kSync ? window_start_ : async_open_), t);
}

std::string format_bounds(const BoundReport& r) {
  std::ostringstream os;
  char b[256];
  std::snprintf(b, sizeof b, "\nThe trace against the analysis (%llu frames): observed next to the bound, in us\n",
                static_cast<unsigned long long>(r.frames));
  os << b;
  std::snprintf(b, sizeof b, "  %-12s %-20s %8s %12s %12s %12s %12s %s\n", "message", "quantity", "frames", "least",
                "most", "bound low", "bound high", "verdict");
  os << b;
  for (const Observation& o : r.observations) {
    if (o.count == 0) {
      std::snprintf(b, sizeof b, "  %-12s %-20s %8s %12s %12s %12.1f %12.1f %s\n", o.message.c_str(),
                    bounded_name(o.quantity), "0", "-", "-", us(o.low), us(o.high), "not seen");
    } else {
      std::snprintf(b, sizeof b, "  %-12s %-20s %8llu %12.1f %12.1f %12.1f %12.1f %s\n", o.message.c_str(),
                    bounded_name(o.quantity), static_cast<unsigned long long>(o.count), us(o.least), us(o.most),
                    us(o.low), us(o.high), o.outside == 0 ? "inside" : "OUTSIDE");
    }
    os << b;
  }
  if (r.ok()) {
    os << "Every observation is inside its bound\n";
  } else {
    std::snprintf(b, sizeof b, "%llu observations OUTSIDE their bounds (the emulation or the analysis is wrong):\n",
                  static_cast<unsigned long long>(r.violation_count));
    os << b;
    for (const BoundViolation& v : r.violations) {
      std::snprintf(b, sizeof b, "  %.6f s  %-12s %s %.1f us, bound %.1f..%.1f us\n", to_seconds(v.time),
                    v.message.c_str(), bounded_name(v.quantity), us(v.observed), us(v.low), us(v.high));
      os << b;
    }
  }
  return os.str();
}

std::string format_bounds_json(const BoundReport& r) {
  std::ostringstream os;
  os << "{\"frames\":" << r.frames << ",\"violation_count\":" << r.violation_count << ",\"observations\":[";
  for (std::size_t i = 0; i < r.observations.size(); ++i) {
    const Observation& o = r.observations[i];
    os << (i ? "," : "") << "{\"message\":" << frames::json_quote(o.message) << ",\"quantity\":\""
       << bounded_name(o.quantity) << "\",\"count\":" << o.count
       << ",\"least_ns\":" << (o.count ? std::to_string(o.least.count()) : "null") << ",\"most_ns\":" << o.most.count()
       << ",\"low_ns\":" << o.low.count() << ",\"high_ns\":" << o.high.count() << ",\"outside\":" << o.outside << "}";
  }
  os << "],\"violations\":[";
  for (std::size_t i = 0; i < r.violations.size(); ++i) {
    const BoundViolation& v = r.violations[i];
    os << (i ? "," : "") << "{\"time_ns\":" << v.time.count() << ",\"message\":" << frames::json_quote(v.message)
       << ",\"quantity\":\"" << bounded_name(v.quantity) << "\",\"observed_ns\":" << v.observed.count()
       << ",\"low_ns\":" << v.low.count() << ",\"high_ns\":" << v.high.count() << "}";
  }
  os << "]}";
  return os.str();
}

}  // namespace canhil::timing
