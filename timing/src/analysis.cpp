#include "canhil/timing/analysis.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "canhil/frames/describe.hpp"
#include "canhil/frames/ftt_slot.hpp"
#include "canhil/frames/wire.hpp"

#include "units.hpp"

namespace canhil::timing {
using units::ms;
using units::us;

const char* kind_name(ViolationKind k) noexcept {
  switch (k) {
    case ViolationKind::kLate:
      return "late";
    case ViolationKind::kMissing:
      return "missing";
    case ViolationKind::kUnscheduled:
      return "unscheduled";
    case ViolationKind::kOutsideWindow:
      return "outside-window";
    case ViolationKind::kTooSoon:
      return "too-soon";
    case ViolationKind::kDuplicate:
      return "duplicate";
  }
  return "?";
}

TimingAnalyzer::TimingAnalyzer(std::shared_ptr<const frames::MessageSet> set, const TimingConfig& config)
    : set_(std::move(set)), config_(config) {
  // Stamps at the end of frame move with each frame's wait for the wire:
  // two sporadic frames sent a minimum gap apart are stamped closer by as
  // much as the second waited less, which one frame on the wire before it
  // (CAN's blocking, the worst-case 8-byte frame) accounts for.
  if (config_.ftt.stamps == frames::StampAt::kEndOfFrame && config_.ftt.bit_rate != 0) {
    gap_slack_ = frames::bits_to_time(frames::worst_case_frame_bits(8), config_.ftt.bit_rate);
  }
  for (const frames::MessageCodec& m : set_->codec().messages()) {
    PerMessage pm;
    pm.codec = &m;
    pm.ftt = set_->ftt(m);
    pm.late_after =
        std::max(config_.late_minimum,
                 Nanos(static_cast<std::int64_t>(config_.late_fraction * static_cast<double>(pm.ftt.period.count()))));
    messages_.push_back(std::move(pm));
  }
}

void TimingAnalyzer::violate(PerMessage& m, Nanos t, ViolationKind k, std::string detail) {
  ++m.violations[k];
  ++report_.violation_count;
  if (report_.violations.size() < TimingReport::kMaxListed) {
    report_.violations.push_back(Violation{t, std::string(m.codec->name()), k, std::move(detail)});
  }
}

void TimingAnalyzer::add(const frames::TimedFrame& tf) {
  const frames::CanFrame& f = tf.frame;
  const Nanos t = tf.time;
  if (report_.frames == 0) report_.start = t;
  report_.end = t;
  ++report_.frames;
  if (!config_.violations_only) report_.bits += frames::frame_bits(f);
  if (f.kind == frames::FrameKind::kError) ++report_.error_frames;
  if (f.kind != frames::FrameKind::kData) return;
  const frames::MessageCodec* codec = set_->codec().find(f.id, f.extended);
  if (codec == nullptr) {
    ++report_.unknown;
    return;
  }
  PerMessage& m = messages_[static_cast<std::size_t>(codec - set_->codec().messages().data())];
  const Nanos ec = config_.ftt.elementary_cycle;
  char detail[160];
  // Intervals: missing and late frames against the period (or the minimum gap).
  if (m.count > 0) {
    const Nanos interval = t - m.last;
    if (!config_.violations_only) m.intervals.push_back(interval);
    if (m.ftt.kind == frames::FttKind::kAsync) {
      if (!frames::keeps_min_gap(t + config_.window_slack + gap_slack_, m.last, m.ftt.min_gap)) {
        std::snprintf(detail, sizeof detail, "%.3f ms after the previous, minimum gap %.0f ms", ms(interval),
                      ms(m.ftt.min_gap));
        violate(m, t, ViolationKind::kTooSoon, detail);
      }
    } else {
      const Nanos period = m.ftt.period;
      const Nanos tolerance = m.late_after;
      if (interval * 2 >= period * 3) {
        const auto missing = static_cast<std::uint64_t>((interval + period / 2) / period) - 1;
        std::snprintf(detail, sizeof detail, "%.3f ms after the previous (period %.0f ms): %llu missing", ms(interval),
                      ms(period), static_cast<unsigned long long>(missing));
        violate(m, t, ViolationKind::kMissing, detail);
      } else if (interval > period + tolerance) {
        std::snprintf(detail, sizeof detail, "%.3f ms after the previous (period %.0f ms)", ms(interval), ms(period));
        violate(m, t, ViolationKind::kLate, detail);
      }
    }
  }
  ++m.count;
  m.last = t;
  // FTT compliance.
  if (m.ftt.kind == frames::FttKind::kTrigger) {
    frames::Tm tm;
    if (set_->tm.decode(f, tm).ok()) {
      have_tm_ = true;
      tm_time_ = frames::ec_start(f, t, config_.ftt);  // the EC's start: the TM's stamp, or before it
      tm_ = tm;
      ++ec_index_;
    }
    return;
  }
  if (!have_tm_) return;  // nothing to judge against yet
  const Nanos in_ec = t - tm_time_;
  const Nanos window_start = frames::sync_window_start(tm_, tm_time_, ec) - tm_time_;  // into the EC
  if (m.ftt.kind == frames::FttKind::kSync) {
    if (((tm_.sync_bitmap >> m.ftt.index) & 1u) == 0) {
      std::snprintf(detail, sizeof detail, "in an EC whose TM (bitmap 0x%X) does not schedule it", tm_.sync_bitmap);
      violate(m, t, ViolationKind::kUnscheduled, detail);
    } else if (in_ec + config_.window_slack < window_start || in_ec >= ec + config_.window_slack) {
      std::snprintf(detail, sizeof detail, "%.1f us into the EC; the synchronous window is %.1f to %.1f us", us(in_ec),
                    us(window_start), us(ec));
      violate(m, t, ViolationKind::kOutsideWindow, detail);
    }
    if (m.last_ec == ec_index_) violate(m, t, ViolationKind::kDuplicate, "twice in one EC");
    m.last_ec = ec_index_;
  } else if (t + config_.window_slack >= frames::async_window_end(tm_, tm_time_, ec)) {
    std::snprintf(detail, sizeof detail, "%.1f us into the EC, inside the synchronous window (from %.1f us)", us(in_ec),
                  us(window_start));
    violate(m, t, ViolationKind::kOutsideWindow, detail);
  }
}

TimingReport TimingAnalyzer::finish() const {
  TimingReport r = report_;
  const double seconds = std::chrono::duration<double>(r.end - r.start).count();
  r.bus_load = seconds > 0 ? static_cast<double>(r.bits) / (seconds * config_.ftt.bit_rate) : 0.0;
  for (const PerMessage& m : messages_) {
    MessageTiming out;
    out.name = std::string(m.codec->name());
    out.id = m.codec->id();
    out.kind = m.ftt.kind;
    out.spec = m.ftt.kind == frames::FttKind::kAsync ? m.ftt.min_gap : m.ftt.period;
    out.count = m.count;
    out.violations = m.violations;
    out.intervals = m.intervals;
    if (!m.intervals.empty()) {
      Nanos sum{0};
      out.min = *std::min_element(m.intervals.begin(), m.intervals.end());
      out.max = *std::max_element(m.intervals.begin(), m.intervals.end());
      for (Nanos i : m.intervals) sum += i;
      out.mean = sum / static_cast<std::int64_t>(m.intervals.size());
      if (m.ftt.kind != frames::FttKind::kAsync) {
        std::vector<Nanos> jitter;
        for (Nanos i : m.intervals) jitter.push_back(i > out.spec ? i - out.spec : out.spec - i);
        std::sort(jitter.begin(), jitter.end());
        auto pct = [&](double p) {
          return jitter[std::min(jitter.size() - 1, static_cast<std::size_t>(p * static_cast<double>(jitter.size())))];
        };
        out.p50 = pct(0.50);
        out.p95 = pct(0.95);
        out.p99 = pct(0.99);
      }
    }
    r.messages.push_back(std::move(out));
  }
  check_capture(r);
  return r;
}

void TimingAnalyzer::check_capture(TimingReport& r) const {
  const MessageTiming* longest = nullptr;
  std::uint64_t triggers = 0;
  for (const MessageTiming& m : r.messages) {
    if (m.kind == frames::FttKind::kTrigger) triggers += m.count;
    if (m.kind != frames::FttKind::kAsync && (longest == nullptr || m.spec > longest->spec)) longest = &m;
  }
  if (longest != nullptr) r.longest_period = longest->spec;
  char text[320];
  if (r.frames == 0 && r.error_frames == 0) {
    r.capture_problems.emplace_back(CaptureProblem::kNoFrames,
                                    "the capture has no frames: check the log's path or that the interface carries "
                                    "traffic (is the emulator or the robot running?)");
    return;
  }
  if (triggers == 0) {
    std::snprintf(text, sizeof text,
                  "the capture has %llu frames but no trigger message (TM): nothing says where the ECs are; is the "
                  "FTT master running, and is this the right interface or DBC?",
                  static_cast<unsigned long long>(r.frames));
    r.capture_problems.emplace_back(CaptureProblem::kNoTrigger, text);
  }
  if (longest != nullptr && r.end - r.start < longest->spec) {
    std::snprintf(text, sizeof text,
                  "the capture is %.1f ms long, shorter than the longest period (%s, %.0f ms): capture for longer",
                  ms(r.end - r.start), longest->name.c_str(), ms(longest->spec));
    r.capture_problems.emplace_back(CaptureProblem::kTooShort, text);
  }
}

std::string format_table(const TimingReport& r) {
  std::ostringstream os;
  char line[256];
  std::snprintf(line, sizeof line, "%-6s %-8s %8s %7s %9s %9s %9s %9s %9s %9s  %s\n", "msg", "kind", "spec ms", "count",
                "mean ms", "min ms", "max ms", "jit p50", "jit p95", "jit p99", "violations");
  os << line;
  for (const MessageTiming& m : r.messages) {
    std::string v;
    for (const auto& [k, n] : m.violations)
      v += std::string(v.empty() ? "" : ", ") + std::to_string(n) + " " + kind_name(k);
    const char* kind = m.kind == frames::FttKind::kTrigger ? "trigger"
                       : m.kind == frames::FttKind::kSync  ? "sync"
                                                           : "async";
    std::snprintf(line, sizeof line, "%-6s %-8s %8.1f %7llu %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f  %s\n", m.name.c_str(),
                  kind, ms(m.spec), static_cast<unsigned long long>(m.count), ms(m.mean), ms(m.min), ms(m.max),
                  ms(m.p50), ms(m.p95), ms(m.p99), v.empty() ? "-" : v.c_str());
    os << line;
  }
  std::snprintf(line, sizeof line,
                "\n%llu frames over %.3f s, %llu unknown, %llu error frames; bus load %.2f %% (%llu bits, stuffing "
                "included)\n",
                static_cast<unsigned long long>(r.frames), std::chrono::duration<double>(r.end - r.start).count(),
                static_cast<unsigned long long>(r.unknown), static_cast<unsigned long long>(r.error_frames),
                100 * r.bus_load, static_cast<unsigned long long>(r.bits));
  os << line;
  for (const auto& [kind, text] : r.capture_problems) os << "capture problem: " << text << "\n";
  if (r.ok()) {
    os << "FTT compliance: no violations\n";
  } else {
    os << "FTT compliance: " << r.violation_count << " violations\n";
    for (const Violation& v : r.violations) {
      std::snprintf(line, sizeof line, "  %.6f %-6s %-15s %s\n", std::chrono::duration<double>(v.time).count(),
                    v.message.c_str(), kind_name(v.kind), v.detail.c_str());
      os << line;
    }
    if (r.violations.size() < r.violation_count)
      os << "  ... (" << r.violation_count - r.violations.size() << " more)\n";
  }
  return os.str();
}

std::string format_json(const TimingReport& r) {
  std::ostringstream os;
  os.precision(9);
  os << "{\"frames\":" << r.frames << ",\"unknown\":" << r.unknown << ",\"error_frames\":" << r.error_frames
     << ",\"duration_s\":" << std::chrono::duration<double>(r.end - r.start).count() << ",\"bits\":" << r.bits
     << ",\"bus_load\":" << r.bus_load << ",\"ok\":" << (r.ok() ? "true" : "false")
     << ",\"violation_count\":" << r.violation_count << ",\"capture_ok\":" << (r.capture_ok() ? "true" : "false")
     << ",\"capture_problems\":[";
  for (std::size_t i = 0; i < r.capture_problems.size(); ++i) {
    os << (i ? "," : "") << frames::json_quote(r.capture_problems[i].second);
  }
  os << "],\"messages\":[";
  for (std::size_t i = 0; i < r.messages.size(); ++i) {
    const MessageTiming& m = r.messages[i];
    os << (i ? "," : "") << "{\"name\":" << frames::json_quote(m.name) << ",\"id\":" << m.id
       << ",\"spec_ms\":" << ms(m.spec) << ",\"count\":" << m.count << ",\"mean_ms\":" << ms(m.mean)
       << ",\"min_ms\":" << ms(m.min) << ",\"max_ms\":" << ms(m.max) << ",\"jitter_p50_ms\":" << ms(m.p50)
       << ",\"jitter_p95_ms\":" << ms(m.p95) << ",\"jitter_p99_ms\":" << ms(m.p99) << ",\"violations\":{";
    bool first = true;
    for (const auto& [k, n] : m.violations) {
      os << (first ? "" : ",") << frames::json_quote(kind_name(k)) << ":" << n;
      first = false;
    }
    os << "}}";
  }
  os << "],\"violations\":[";
  for (std::size_t i = 0; i < r.violations.size(); ++i) {
    const Violation& v = r.violations[i];
    os << (i ? "," : "") << "{\"time\":" << std::chrono::duration<double>(v.time).count()
       << ",\"message\":" << frames::json_quote(v.message) << ",\"kind\":" << frames::json_quote(kind_name(v.kind))
       << ",\"detail\":" << frames::json_quote(v.detail) << "}";
  }
  os << "]}";
  return os.str();
}

}  // namespace canhil::timing
