// The analysis of a message set as a table for people and as JSON.
#include <cstdio>
#include <sstream>

#include "canhil/frames/describe.hpp"
#include "canhil/timing/bus_analysis.hpp"
#include "units.hpp"

namespace canhil::timing {
namespace {

using frames::FttKind;

using units::id_text;
using units::us;

std::string us_or_never(Nanos t) {
  if (t == kNever) return "unbounded";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", us(t));
  return b;
}

const char* kind_text(FttKind k, bool ftt) {
  if (k == FttKind::kTrigger) return "trigger";
  if (k == FttKind::kSync) return ftt ? "sync" : "periodic";
  return ftt ? "async" : "sporadic";
}

std::string names_of(const BusAnalysis& a, std::uint32_t bitmap) {
  std::string out;
  for (const SyncBound& m : a.sync.messages) {
    if ((bitmap >> m.index) & 1u) out += (out.empty() ? "" : " ") + m.name;
  }
  return out;
}

// A line of printf-formatted text.
template <class... T>
void line(std::ostringstream& os, const char* format, T... values) {
  char b[512];
  std::snprintf(b, sizeof b, format, values...);
  os << b << '\n';
}

void frames_table(std::ostringstream& os, const BusAnalysis& a) {
  os << "Frame times (interframe space included; worst case: every stuff bit the frame allows)\n";
  line(os, "  %-12s %-10s %-8s %3s %9s %10s %9s %10s", "message", "id", "kind", "dlc", "best bits", "worst bits",
       "best us", "worst us");
  for (const FrameRow& f : a.frames) {
    line(os, "  %-12s %-10s %-8s %3u %9u %10u %9.1f %10.1f", f.name.c_str(), id_text(f.id, f.extended).c_str(),
         kind_text(f.kind, a.ftt), f.dlc, f.time.best_bits, f.time.worst_bits, us(f.time.best), us(f.time.worst));
  }
}

void sync_table(std::ostringstream& os, const BusAnalysis& a) {
  const SyncAnalysis& s = a.sync;
  const Nanos ec = a.config.ftt.elementary_cycle;
  line(os, "\nSynchronous traffic: the master's schedule repeats every %llu ECs (%.1f ms)",
       static_cast<unsigned long long>(s.cycle_ecs), us(ec) * static_cast<double>(s.cycle_ecs) / 1e3);
  constexpr std::size_t kShown = 40;
  line(os, "  %4s %10s  %s", "EC", "window us", "messages due (window: their frames + the guard)");
  for (std::size_t k = 0; k < s.ecs.size() && k < kShown; ++k) {
    line(os, "  %4llu %10.1f  %s", static_cast<unsigned long long>(s.ecs[k].ec), us(s.ecs[k].window),
         names_of(a, s.ecs[k].bitmap).c_str());
  }
  if (s.cycle_ecs > kShown)
    line(os, "  ... %llu more ECs (--json lists them)", static_cast<unsigned long long>(s.cycle_ecs - kShown));
  line(os, "  worst EC %llu: %.1f us of the %.1f us allowed (LSW%s): %s, %.1f us %s",
       static_cast<unsigned long long>(s.worst_ec), us(s.longest_window), us(s.allowed_window),
       a.config.sync_window ? ", --sync-window-us" : " = EC - TM - the longest asynchronous frame",
       s.fits ? "fits" : "DOES NOT FIT",
       us(s.fits ? s.allowed_window - s.longest_window : s.longest_window - s.allowed_window),
       s.fits ? "left" : "over");
  line(os,
       "  utilisation %.4f; rate-monotonic test of Almeida, Pedreiras & Fonseca, U < n(2^(1/n)-1)(LSW-guard-X)/E "
       "= %.4f (X = %.1f us): %s, margin %+.4f",
       s.utilisation, s.utilisation_bound, us(s.longest_frame), s.utilisation_test ? "passes" : "fails",
       s.utilisation_bound - s.utilisation);
  line(os, "  %-12s %-10s %5s %10s %9s %15s %8s %s", "message", "id", "index", "period ms", "wire us", "worst end us",
       "worst EC", "in its windows");
  for (const SyncBound& m : s.messages) {
    line(os, "  %-12s %-10s %5d %10.1f %9.1f %15.1f %8llu %s", m.name.c_str(), id_text(m.id, false).c_str(), m.index,
         us(m.period) / 1e3, us(m.wire), us(m.worst_offset), static_cast<unsigned long long>(m.worst_ec),
         m.fits ? "fits" : "DOES NOT FIT");
  }
}

void async_table(std::ostringstream& os, const BusAnalysis& a) {
  const AsyncAnalysis& s = a.async;
  line(os,
       "\nSporadic traffic in the asynchronous window: shortest window %.1f us, idle time inserted at its end %.1f us, "
       "%.1f us served per EC (%.0f %% of it); a message ready waits up to %.1f us for the next window",
       us(s.shortest_window), us(s.idle_inserted), us(s.usable), 100 * s.share, us(s.wait));
  line(os, "  %-12s %-10s %8s %10s %10s %10s %13s %13s %7s %12s %s", "message", "id", "wire us", "min gap ms",
       "deadline", "blocking", "from window", "worst resp.", "windows", "margin us", "verdict");
  for (const AsyncBound& m : s.messages) {
    line(os, "  %-12s %-10s %8.1f %10.1f %10.1f %10.1f %13s %13s %7d %12s %s", m.name.c_str(),
         id_text(m.id, m.extended).c_str(), us(m.wire), us(m.min_gap) / 1e3, us(m.deadline) / 1e3, us(m.blocking),
         us_or_never(m.from_window).c_str(), us_or_never(m.worst_response).c_str(), m.windows,
         m.worst_response == kNever ? "-" : us_or_never(m.margin()).c_str(), m.schedulable ? "meets" : "MISSES");
  }
  os << "  (from window: from the window's opening to the frame's end; worst resp.: from ready, the wait included; "
        "deadlines in ms)\n";
}

void native_table(std::ostringstream& os, const BusAnalysis& a) {
  const NativeAnalysis& n = a.native;
  line(os, "\nNative CAN response times (Davis, Burns, Bril & Lukkien 2007): utilisation %.4f", n.utilisation);
  line(os, "  %-12s %-10s %8s %10s %10s %10s %12s %9s %13s %12s %s", "message", "id", "wire us", "period ms",
       "deadline", "blocking", "busy period", "instances", "worst resp.", "margin us", "verdict");
  for (const ResponseBound& m : n.messages) {
    line(os, "  %-12s %-10s %8.1f %10.1f %10.1f %10.1f %12s %9d %13s %12s %s", m.name.c_str(),
         id_text(m.id, m.extended).c_str(), us(m.transmission), us(m.period) / 1e3, us(m.deadline) / 1e3,
         us(m.blocking), us_or_never(m.busy_period).c_str(), m.instances, us_or_never(m.worst_response).c_str(),
         m.worst_response == kNever ? "-" : us_or_never(m.margin()).c_str(), m.schedulable ? "meets" : "MISSES");
  }
}

void what_if_table(std::ostringstream& os, const BusAnalysis& a) {
  const WhatIf& w = a.what_if;
  os << "\nWhat-if (everything else as analysed)\n";
  if (w.lowest_bit_rate == 0) {
    line(os, "  lowest bit rate: none up to %u bit/s", WhatIf::kHighestBitRate);
  } else {
    line(os, "  lowest bit rate: %u bit/s (analysed at %u)", w.lowest_bit_rate, a.config.ftt.bit_rate);
  }
  if (a.ftt) {
    if (w.shortest_ec == Nanos{0}) {
      os << "  shortest EC: none that divides every synchronous period\n";
    } else {
      line(os, "  shortest EC (one that divides every synchronous period): %.0f us (analysed at %.0f)",
           us(w.shortest_ec), us(a.config.ftt.elementary_cycle));
    }
  }
  for (const CopiesLimit& c : w.copies) {
    line(os, "  %-12s %4d more copies fit%s%s", c.name.c_str(), c.copies,
         c.limited == "schedulability" ? "" : "; limited by ", c.limited == "schedulability" ? "" : c.limited.c_str());
  }
  if (w.copies.empty() && a.config.what_if) os << "  copies: name messages with --copies NAME\n";
}

}  // namespace

std::string format_analysis(const BusAnalysis& a) {
  std::ostringstream os;
  if (a.ftt) {
    line(os, "FTT-CAN message set: EC %.0f us, %u bit/s, synchronous window guard %.0f us",
         us(a.config.ftt.elementary_cycle), a.config.ftt.bit_rate, us(a.config.ftt.sync_window_guard));
  } else {
    line(os, "Native CAN message set (no trigger message): %u bit/s", a.config.ftt.bit_rate);
  }
  frames_table(os, a);
  if (a.ftt) {
    sync_table(os, a);
    async_table(os, a);
  } else {
    native_table(os, a);
  }
  if (a.config.what_if) what_if_table(os, a);
  if (a.schedulable()) {
    os << "\nSchedulable: every message meets its deadline in the worst case\n";
  } else {
    os << "\nNOT schedulable:\n";
    for (const Miss& m : a.misses) {
      const bool by = m.by > Nanos{0} && m.by != kNever;
      os << "  " << m.name << (by ? " misses by " + us_or_never(m.by) + " us" : "") << ": " << m.why << '\n';
    }
  }
  return os.str();
}

std::string format_analysis_json(const BusAnalysis& a) {
  std::ostringstream os;
  auto ns = [](Nanos t) { return t == kNever ? std::string("null") : std::to_string(t.count()); };
  os << "{\"ftt\":" << (a.ftt ? "true" : "false") << ",\"bit_rate\":" << a.config.ftt.bit_rate
     << ",\"elementary_cycle_ns\":" << a.config.ftt.elementary_cycle.count() << ",\"frames\":[";
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    const FrameRow& f = a.frames[i];
    os << (i ? "," : "") << "{\"name\":" << frames::json_quote(f.name) << ",\"id\":" << f.id
       << ",\"extended\":" << (f.extended ? "true" : "false") << ",\"kind\":\"" << kind_text(f.kind, a.ftt)
       << "\",\"dlc\":" << int{f.dlc} << ",\"best_bits\":" << f.time.best_bits
       << ",\"worst_bits\":" << f.time.worst_bits << ",\"best_ns\":" << f.time.best.count()
       << ",\"worst_ns\":" << f.time.worst.count() << "}";
  }
  os << "]";
  if (a.ftt) {
    const SyncAnalysis& s = a.sync;
    os << ",\"sync\":{\"cycle_ecs\":" << s.cycle_ecs << ",\"worst_ec\":" << s.worst_ec
       << ",\"longest_window_ns\":" << s.longest_window.count() << ",\"allowed_window_ns\":" << s.allowed_window.count()
       << ",\"fits\":" << (s.fits ? "true" : "false") << ",\"utilisation\":" << s.utilisation
       << ",\"utilisation_bound\":" << s.utilisation_bound
       << ",\"utilisation_test\":" << (s.utilisation_test ? "true" : "false") << ",\"ecs\":[";
    for (std::size_t i = 0; i < s.ecs.size(); ++i) {
      os << (i ? "," : "") << "{\"ec\":" << s.ecs[i].ec << ",\"bitmap\":" << s.ecs[i].bitmap
         << ",\"window_ns\":" << s.ecs[i].window.count() << "}";
    }
    os << "],\"messages\":[";
    for (std::size_t i = 0; i < s.messages.size(); ++i) {
      const SyncBound& m = s.messages[i];
      os << (i ? "," : "") << "{\"name\":" << frames::json_quote(m.name) << ",\"id\":" << m.id
         << ",\"index\":" << m.index << ",\"period_ns\":" << m.period.count() << ",\"wire_ns\":" << m.wire.count()
         << ",\"worst_offset_ns\":" << m.worst_offset.count() << ",\"worst_ec\":" << m.worst_ec
         << ",\"fits\":" << (m.fits ? "true" : "false") << "}";
    }
    const AsyncAnalysis& as = a.async;
    os << "]},\"async\":{\"shortest_window_ns\":" << as.shortest_window.count()
       << ",\"idle_inserted_ns\":" << as.idle_inserted.count() << ",\"usable_ns\":" << as.usable.count()
       << ",\"wait_ns\":" << as.wait.count() << ",\"share\":" << as.share << ",\"messages\":[";
    for (std::size_t i = 0; i < as.messages.size(); ++i) {
      const AsyncBound& m = as.messages[i];
      os << (i ? "," : "") << "{\"name\":" << frames::json_quote(m.name) << ",\"id\":" << m.id
         << ",\"wire_ns\":" << m.wire.count() << ",\"min_gap_ns\":" << m.min_gap.count()
         << ",\"deadline_ns\":" << m.deadline.count() << ",\"blocking_ns\":" << m.blocking.count()
         << ",\"from_window_ns\":" << ns(m.from_window) << ",\"worst_response_ns\":" << ns(m.worst_response)
         << ",\"windows\":" << m.windows << ",\"schedulable\":" << (m.schedulable ? "true" : "false") << "}";
    }
    os << "]}";
  } else {
    const NativeAnalysis& n = a.native;
    os << ",\"native\":{\"utilisation\":" << n.utilisation << ",\"messages\":[";
    for (std::size_t i = 0; i < n.messages.size(); ++i) {
      const ResponseBound& m = n.messages[i];
      os << (i ? "," : "") << "{\"name\":" << frames::json_quote(m.name) << ",\"id\":" << m.id
         << ",\"wire_ns\":" << m.transmission.count() << ",\"period_ns\":" << m.period.count()
         << ",\"deadline_ns\":" << m.deadline.count() << ",\"blocking_ns\":" << m.blocking.count()
         << ",\"busy_period_ns\":" << ns(m.busy_period) << ",\"instances\":" << m.instances
         << ",\"worst_response_ns\":" << ns(m.worst_response)
         << ",\"schedulable\":" << (m.schedulable ? "true" : "false") << "}";
    }
    os << "]}";
  }
  if (a.config.what_if) {
    const WhatIf& w = a.what_if;
    os << ",\"what_if\":{\"lowest_bit_rate\":" << w.lowest_bit_rate << ",\"shortest_ec_ns\":" << w.shortest_ec.count()
       << ",\"copies\":[";
    for (std::size_t i = 0; i < w.copies.size(); ++i) {
      os << (i ? "," : "") << "{\"name\":" << frames::json_quote(w.copies[i].name)
         << ",\"copies\":" << w.copies[i].copies << ",\"limited_by\":" << frames::json_quote(w.copies[i].limited)
         << "}";
    }
    os << "]}";
  }
  os << ",\"schedulable\":" << (a.schedulable() ? "true" : "false") << ",\"misses\":[";
  for (std::size_t i = 0; i < a.misses.size(); ++i) {
    os << (i ? "," : "") << "{\"name\":" << frames::json_quote(a.misses[i].name) << ",\"by_ns\":" << ns(a.misses[i].by)
       << ",\"why\":" << frames::json_quote(a.misses[i].why) << "}";
  }
  os << "]}";
  return os.str();
}

}  // namespace canhil::timing
