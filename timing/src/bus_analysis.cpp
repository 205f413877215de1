#include "canhil/timing/bus_analysis.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/wire.hpp"
#include "units.hpp"

namespace canhil::timing {
namespace {

using frames::FttKind;

// A service time longer than this is taken as unbounded (a set whose sporadic
// load the windows cannot carry).
constexpr Nanos kLongestService = std::chrono::hours(1);

std::string us_text(Nanos t) {
  char b[32];
  std::snprintf(b, sizeof b, "%.0f us", static_cast<double>(t.count()) / 1e3);
  return b;
}

using units::ceil_div;
using units::id_text;

AnalysedMessage analysed(const BusMessage& m, Nanos wire) {
  return {m.name, m.id, m.extended, wire, m.spacing(), m.deadline, Nanos{0}};
}

// Arbitration order (frames/wire.hpp's, as wins_arbitration), without a copy of either message.
bool before(const BusMessage& a, const BusMessage& b) noexcept {
  return frames::arbitration_key(a.id, a.extended) < frames::arbitration_key(b.id, b.extended);
}

Nanos wire_of(const BusMessage& m, std::uint32_t bit_rate) { return frame_time(m.dlc, m.extended, bit_rate).worst; }

// The time from a window's opening to serve `demand` when each EC serves
// `usable` of it, the rest of the EC closed to it.
Nanos served(Nanos demand, Nanos usable, Nanos ec, int* windows) noexcept {
  const std::int64_t full = ceil_div(demand, usable) - 1;  // windows filled before the last
  *windows = static_cast<int>(full + 1);
  return full * ec + (demand - full * usable);
}

void analyse_sync(const BusSet& set, const frames::FttSchedule& schedule, const AnalysisConfig& config,
                  BusAnalysis& a) {
  SyncAnalysis& s = a.sync;
  const Nanos ec = config.ftt.elementary_cycle;
  s.cycle_ecs = schedule.cycle_ecs();
  s.worst_ec = schedule.worst_ec();
  s.longest_window = schedule.longest_sync_window();
  s.guard = config.ftt.sync_window_guard;
  s.allowed_window = config.sync_window.value_or(ec - schedule.trigger_wire() - schedule.longest_async_wire());
  s.fits = s.longest_window <= s.allowed_window;
  // Synchronous messages by index, and the indices in arbitration order.
  std::vector<const BusMessage*> by_index(32, nullptr);
  std::vector<int> order;
  for (const BusMessage& m : set.messages) {
    if (m.kind != FttKind::kSync) continue;
    by_index[static_cast<std::size_t>(m.index)] = &m;
    order.push_back(m.index);
  }
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    return before(*by_index[static_cast<std::size_t>(x)], *by_index[static_cast<std::size_t>(y)]);
  });
  std::vector<SyncBound> bound(32);
  // Each message's window start and latest end in the ECs it is due in, in order.
  struct Slot {
    Nanos start;
    Nanos end;
  };
  std::vector<std::vector<Slot>> slots(32);
  for (int i : order) {
    const BusMessage& m = *by_index[static_cast<std::size_t>(i)];
    SyncBound& b = bound[static_cast<std::size_t>(i)];
    b.name = m.name;
    b.id = m.id;
    b.index = i;
    b.period = m.period;
    b.wire = wire_of(m, config.ftt.bit_rate);
    s.utilisation += to_seconds(b.wire) / to_seconds(m.period);
    s.longest_frame = std::max(s.longest_frame, b.wire);
  }
  for (std::uint64_t k = 0; k < s.cycle_ecs; ++k) {
    const std::uint32_t bitmap = schedule.bitmap(k);
    const Nanos window = schedule.sync_window(bitmap);
    if (s.ecs.size() < SyncAnalysis::kMostListed) s.ecs.push_back({k, bitmap, window});
    Nanos offset{0};
    for (int i : order) {
      if (((bitmap >> i) & 1u) == 0) continue;
      SyncBound& b = bound[static_cast<std::size_t>(i)];
      offset += b.wire;
      if (slots[static_cast<std::size_t>(i)].size() < SyncAnalysis::kMostListed) {
        slots[static_cast<std::size_t>(i)].push_back({ec - window, offset});
      }
      if (offset > b.worst_offset) {
        b.worst_offset = offset;
        b.worst_ec = k;
      }
      b.longest_window = std::max(b.longest_window, window);
    }
  }
  for (int i : order) {
    SyncBound& b = bound[static_cast<std::size_t>(i)];
    // From one of its ECs to the next (the last to the first of the next cycle).
    const std::vector<Slot>& sl = slots[static_cast<std::size_t>(i)];
    b.interval_low = b.interval_high = b.period;
    for (std::size_t k = 0; k < sl.size(); ++k) {
      const Slot& from = sl[k];
      const Slot& to = sl[(k + 1) % sl.size()];
      b.interval_low = std::min(b.interval_low, b.period + to.start - from.start - from.end);
      b.interval_high = std::max(b.interval_high, b.period + to.start + to.end - from.start);
    }
    b.fits = b.longest_window <= s.allowed_window;
    if (!b.fits) {
      a.misses.push_back({b.name, b.longest_window - s.allowed_window,
                          "a synchronous window it is in (" + us_text(b.longest_window) +
                              ") is longer than the longest allowed (" + us_text(s.allowed_window) + ")"});
    }
    s.messages.push_back(b);
  }
  const auto n = static_cast<double>(order.size());
  if (n > 0) {
    const double room = to_seconds(s.allowed_window - s.guard - s.longest_frame) / to_seconds(ec);
    s.utilisation_bound = std::max(0.0, n * (std::exp2(1.0 / n) - 1.0) * room);
    s.utilisation_test = s.utilisation < s.utilisation_bound;
  } else {
    s.utilisation_test = true;
  }
}

void analyse_async(const BusSet& set, const frames::FttSchedule& schedule, const AnalysisConfig& config,
                   BusAnalysis& a) {
  AsyncAnalysis& s = a.async;
  const Nanos ec = config.ftt.elementary_cycle;
  const Nanos bit = frames::bits_to_time(1, config.ftt.bit_rate);
  s.shortest_window = ec - schedule.trigger_wire() - schedule.longest_sync_window();
  if (config.sync_window)
    s.shortest_window = std::min(s.shortest_window, ec - schedule.trigger_wire() - *config.sync_window);
  s.idle_inserted = schedule.longest_async_wire();
  s.usable = std::max(Nanos{0}, s.shortest_window - s.idle_inserted);
  s.wait = ec + schedule.trigger_wire();
  s.share = to_seconds(s.usable) / to_seconds(ec);
  std::vector<BusMessage> async;
  for (const BusMessage& m : set.messages) {
    if (m.kind == FttKind::kAsync) async.push_back(m);
  }
  std::stable_sort(async.begin(), async.end(), before);
  std::vector<Nanos> wire;
  for (const BusMessage& m : async) {
    wire.push_back(wire_of(m, config.ftt.bit_rate));
    s.utilisation += to_seconds(wire.back()) / to_seconds(m.min_gap);
  }
  for (std::size_t i = 0; i < async.size(); ++i) {
    const BusMessage& m = async[i];
    AsyncBound b;
    b.name = m.name;
    b.id = m.id;
    b.extended = m.extended;
    b.wire = wire[i];
    b.min_gap = m.min_gap;
    b.deadline = m.deadline > Nanos{0} ? m.deadline : m.min_gap;
    for (std::size_t k = i + 1; k < async.size(); ++k) b.blocking = std::max(b.blocking, wire[k]);
    b.from_window = b.worst_response = kNever;
    if (s.usable >= b.wire) {
      // Real time R from the window's opening: the demand queued in it (the
      // higher-priority frames queued up to a bit time later, each released
      // up to one EC late by the wait for its window), served window by window.
      Nanos r = b.wire;
      for (;;) {
        Nanos demand = b.blocking + b.wire;
        for (std::size_t k = 0; k < i; ++k) demand += ceil_div(r + ec + bit, async[k].min_gap) * wire[k];
        int windows = 0;
        const Nanos next = served(demand, s.usable, ec, &windows);
        b.windows = windows;
        if (next > kLongestService) break;
        if (next == r) {
          b.from_window = r;
          break;
        }
        r = next;
      }
    }
    // Beyond its own minimum gap a second instance would be queued behind it:
    // this analysis does not go on, and such a message misses.
    if (b.from_window != kNever && b.from_window <= b.min_gap) b.worst_response = b.from_window + s.wait;
    b.schedulable = b.worst_response <= b.deadline;
    if (!b.schedulable) {
      a.misses.push_back({b.name, b.worst_response == kNever ? kNever : b.worst_response - b.deadline,
                          b.worst_response == kNever ? "the asynchronous windows cannot carry it"
                                                     : "its worst-case response passes its deadline"});
    }
    s.messages.push_back(b);
  }
}

BusAnalysis analyse_once(const BusSet& set, const AnalysisConfig& config) {
  if (config.ftt.bit_rate == 0) throw SetupError("the bit rate must be positive");
  BusAnalysis a;
  a.ftt = set.ftt;
  a.config = config;
  std::vector<BusMessage> ordered = set.messages;
  std::stable_sort(ordered.begin(), ordered.end(), before);
  for (const BusMessage& m : ordered)
    a.frames.push_back({m.name, m.id, m.extended, m.dlc, m.kind, frame_time(m.dlc, m.extended, config.ftt.bit_rate)});
  if (!set.ftt) {
    std::vector<AnalysedMessage> msgs;
    for (const BusMessage& m : set.messages) msgs.push_back(analysed(m, wire_of(m, config.ftt.bit_rate)));
    a.native = analyse_native_can(std::move(msgs), config.ftt.bit_rate);
    for (const ResponseBound& r : a.native.messages) {
      if (!r.schedulable) {
        a.misses.push_back({r.name, r.worst_response == kNever ? kNever : r.worst_response - r.deadline,
                            r.worst_response == kNever ? "the messages of its priority and above need the whole bus"
                                                       : "its worst-case response passes its deadline"});
      }
    }
    return a;
  }
  std::vector<frames::FttEntry> entries;
  for (const BusMessage& m : set.messages) {
    // The trigger message is the EC: its period is the EC being analysed.
    entries.push_back({m.name, m.kind, m.index, m.kind == FttKind::kTrigger ? config.ftt.elementary_cycle : m.period,
                       wire_of(m, config.ftt.bit_rate)});
  }
  const frames::FttSchedule schedule(entries, config.ftt, frames::FttSchedule::Fit::kReport);
  a.misfit = schedule.misfit();
  if (!a.misfit.empty()) a.misses.push_back({"the FTT master", Nanos{0}, a.misfit});
  analyse_sync(set, schedule, config, a);
  analyse_async(set, schedule, config, a);
  return a;
}

bool schedulable(const BusSet& set, const AnalysisConfig& config) {
  try {
    return analyse_once(set, config).schedulable();
  } catch (const SetupError&) {
    return false;
  }
}

// The identifiers free after `m`'s (next lower priority), `count` of them.
std::vector<std::uint32_t> free_ids_after(const BusSet& set, const BusMessage& m, int count) {
  std::vector<std::uint32_t> out;
  const std::uint32_t top = m.extended ? 0x1FFFFFFFu : 0x7FFu;
  for (std::uint32_t id = m.id + 1; id <= top && static_cast<int>(out.size()) < count; ++id) {
    const bool used = std::any_of(set.messages.begin(), set.messages.end(),
                                  [&](const BusMessage& o) { return o.id == id && o.extended == m.extended; });
    if (!used) out.push_back(id);
  }
  return out;
}

int free_indices(const BusSet& set) {
  std::uint32_t used = 0;
  for (const BusMessage& m : set.messages) {
    if (m.kind == FttKind::kSync && set.ftt) used |= 1u << m.index;
  }
  return 32 - std::popcount(used);
}

BusSet with_copies(const BusSet& set, const BusMessage& m, int copies, const std::vector<std::uint32_t>& ids) {
  BusSet out = set;
  int index = 0;
  for (int c = 0; c < copies; ++c) {
    BusMessage copy = m;
    copy.name = m.name + "#" + std::to_string(c + 1);
    copy.id = ids[static_cast<std::size_t>(c)];
    if (set.ftt && m.kind == FttKind::kSync) {
      while (std::any_of(out.messages.begin(), out.messages.end(),
                         [&](const BusMessage& o) { return o.kind == FttKind::kSync && o.index == index; }))
        ++index;
      copy.index = index;
    }
    out.messages.push_back(copy);
  }
  return out;
}

CopiesLimit copies_limit(const BusSet& set, const BusMessage& m, const AnalysisConfig& config) {
  constexpr int kMostCopies = 1000;
  CopiesLimit out{m.name, 0, "schedulability"};
  int cap = kMostCopies;
  if (set.ftt && m.kind == FttKind::kSync) cap = std::min(cap, free_indices(set));
  const std::vector<std::uint32_t> ids = free_ids_after(set, m, cap);
  if (static_cast<int>(ids.size()) < cap) cap = static_cast<int>(ids.size());
  auto fits = [&](int k) { return schedulable(with_copies(set, m, k, ids), config); };
  // Grow until a count fails, then halve the gap.
  int good = 0;
  int bad = -1;
  for (int k = 1; k <= cap; k = std::min(cap, k * 2)) {
    if (!fits(k)) {
      bad = k;
      break;
    }
    good = k;
    if (k == cap) break;
  }
  if (bad < 0) {
    out.copies = good;
    if (good == cap) {
      out.limited = cap == kMostCopies                    ? "the count, which stops at " + std::to_string(kMostCopies)
                    : set.ftt && m.kind == FttKind::kSync ? "the free FTT indices (32 in all)"
                                                          : "the free identifiers after it";
    }
    return out;
  }
  while (bad - good > 1) {
    const int mid = good + (bad - good) / 2;
    (fits(mid) ? good : bad) = mid;
  }
  out.copies = good;
  return out;
}

std::vector<Nanos> ec_candidates(const BusSet& set, const AnalysisConfig& config) {
  // An EC divides every synchronous period: the divisors of their greatest
  // common divisor, in microseconds, shortest first; none shorter than EC 0
  // needs (every synchronous message is due in it, with the TM and one
  // sporadic frame), which also keeps the schedule cycles to analyse short.
  std::int64_t g = 0;
  Nanos least = config.ftt.sync_window_guard;
  Nanos longest_async{0};
  for (const BusMessage& m : set.messages) {
    const Nanos wire = wire_of(m, config.ftt.bit_rate);
    if (m.kind == FttKind::kSync) {
      g = std::gcd(g, std::chrono::duration_cast<std::chrono::microseconds>(m.period).count());
      least += wire;
    } else if (m.kind == FttKind::kTrigger) {
      least += wire;
    } else {
      longest_async = std::max(longest_async, wire);
    }
  }
  least += longest_async;
  std::vector<Nanos> out;
  if (g <= 0) return out;
  for (std::int64_t d = 1; d * d <= g; ++d) {
    if (g % d != 0) continue;
    for (const std::int64_t e : {d, g / d}) {
      if (std::chrono::microseconds(e) >= least) out.push_back(std::chrono::microseconds(e));
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

WhatIf what_if(const BusSet& set, const AnalysisConfig& config) {
  WhatIf w;
  AnalysisConfig c = config;
  c.what_if = false;
  AnalysisConfig at = c;
  at.ftt.bit_rate = WhatIf::kHighestBitRate;
  if (schedulable(set, at)) {
    std::uint32_t lo = WhatIf::kLowestBitRate;   // lowest candidate
    std::uint32_t hi = WhatIf::kHighestBitRate;  // schedulable
    at.ftt.bit_rate = lo;
    if (schedulable(set, at)) {
      hi = lo;
    } else {
      while (hi - lo > 1) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        at.ftt.bit_rate = mid;
        (schedulable(set, at) ? hi : lo) = mid;
      }
    }
    w.lowest_bit_rate = hi;
  }
  if (set.ftt) {
    for (const Nanos ec : ec_candidates(set, c)) {
      at = c;
      at.ftt.elementary_cycle = ec;
      if (schedulable(set, at)) {
        w.shortest_ec = ec;
        break;
      }
    }
  }
  const bool base_ok = schedulable(set, c);
  std::vector<std::string> names = config.copies_of;
  if (names.empty() && set.messages.size() <= AnalysisConfig::kDefaultCopies) {
    for (const BusMessage& m : set.messages) {
      if (m.kind != FttKind::kTrigger) names.push_back(m.name);
    }
  }
  for (const std::string& name : names) {
    const auto it =
        std::find_if(set.messages.begin(), set.messages.end(), [&](const BusMessage& m) { return m.name == name; });
    if (it == set.messages.end()) throw SetupError("--copies " + name + ": the message set has no message " + name);
    if (it->kind == FttKind::kTrigger) throw SetupError("--copies " + name + ": there is one trigger message");
    w.copies.push_back(base_ok ? copies_limit(set, *it, c) : CopiesLimit{name, 0, "the set, which misses already"});
  }
  return w;
}

std::uint32_t parse_id(const std::string& text, const std::string& field) {
  try {
    std::size_t used = 0;
    const unsigned long long v =
        std::stoull(text, &used, text.rfind("0x", 0) == 0 || text.rfind("0X", 0) == 0 ? 16 : 10);
    if (used == text.size() && v <= 0x1FFFFFFFull) return static_cast<std::uint32_t>(v);
  } catch (const std::exception&) {
  }
  throw SetupError(field + ": \"" + text + "\" is not a CAN identifier (decimal or 0x hex, at most 0x1FFFFFFF)");
}

}  // namespace

BusSet read_bus_set(const frames::Database& db) {
  BusSet set;
  set.ftt = std::any_of(db.messages.begin(), db.messages.end(), [](const frames::MessageDef& m) {
    return m.attribute_text("FttKind").value_or("") == "trigger";
  });
  for (const frames::MessageDef& d : db.messages) {
    BusMessage m;
    m.name = d.name;
    m.id = d.id;
    m.extended = d.extended;
    m.dlc = d.length;
    if (const auto ms = d.attribute_int("GenMsgDeadline"); ms && *ms > 0) m.deadline = std::chrono::milliseconds(*ms);
    if (set.ftt) {
      const frames::FttInfo info = frames::read_ftt(d, db.file);
      m.kind = info.kind;
      m.index = info.index;
      m.period = info.period;
      m.min_gap = info.min_gap;
    } else if (const auto period = d.attribute_int("GenMsgCycleTime"); period && *period > 0) {
      m.kind = FttKind::kSync;
      m.period = std::chrono::milliseconds(*period);
    } else if (const auto gap = d.attribute_int("GenMsgDelayTime"); gap && *gap > 0) {
      m.min_gap = std::chrono::milliseconds(*gap);
    } else {
      throw frames::DbcError(db.file, d.line,
                             "message " + d.name +
                                 " has neither a period nor a minimum gap; set BA_ \"GenMsgCycleTime\" BO_ " +
                                 std::to_string(d.id) + " <ms>; (periodic) or BA_ \"GenMsgDelayTime\" BO_ " +
                                 std::to_string(d.id) + " <ms>; (sporadic)");
    }
    set.messages.push_back(m);
  }
  return set;
}

void add_message(BusSet& set, std::string_view text) {
  std::istringstream in{std::string(text)};
  std::vector<std::string> f;
  for (std::string w; in >> w;) f.push_back(w);
  const std::string where = "--add \"" + std::string(text) + "\"";
  if (f.size() != 5) {
    throw SetupError(where + ": expected NAME ID DLC PERIOD_MS sync|async, got " + std::to_string(f.size()) +
                     " fields");
  }
  BusMessage m;
  m.name = f[0];
  m.id = parse_id(f[1], where + ": ID");
  m.extended = m.id > 0x7FF;
  if (f[2].size() != 1 || f[2][0] < '0' || f[2][0] > '8') {
    throw SetupError(where + ": DLC: \"" + f[2] + "\" is not a classic CAN length (0 to 8 data bytes)");
  }
  m.dlc = static_cast<std::uint8_t>(f[2][0] - '0');
  double ms = 0;
  try {
    std::size_t used = 0;
    ms = std::stod(f[3], &used);
    if (used != f[3].size()) ms = 0;
  } catch (const std::exception&) {
    ms = 0;
  }
  if (!(ms > 0) || ms > 3.6e6) {
    throw SetupError(where + ": PERIOD_MS: \"" + f[3] + "\" is not a period in milliseconds (a positive number)");
  }
  const Nanos spacing = std::chrono::duration_cast<Nanos>(std::chrono::duration<double, std::milli>(ms));
  if (f[4] == "sync") {
    m.kind = FttKind::kSync;
    m.period = spacing;
  } else if (f[4] == "async") {
    m.kind = FttKind::kAsync;
    m.min_gap = spacing;
  } else {
    throw SetupError(where + ": KIND: \"" + f[4] + "\" is neither sync (periodic) nor async (sporadic)");
  }
  for (const BusMessage& o : set.messages) {
    if (o.name == m.name) throw SetupError(where + ": NAME: the message set already has a message " + m.name);
    if (o.id == m.id && o.extended == m.extended) {
      throw SetupError(where + ": ID: " + id_text(m.id, m.extended) + " is " + o.name +
                       "'s; two senders of one identifier collide in arbitration");
    }
  }
  if (set.ftt && m.kind == FttKind::kSync) {
    for (m.index = 0; m.index < 32; ++m.index) {
      if (std::none_of(set.messages.begin(), set.messages.end(),
                       [&](const BusMessage& o) { return o.kind == FttKind::kSync && o.index == m.index; }))
        break;
    }
    if (m.index == 32) throw SetupError(where + ": KIND: all 32 FTT indices (TM.sync_bitmap bits) are taken");
  }
  set.messages.push_back(m);
}

BusAnalysis analyse_bus(const BusSet& set, const AnalysisConfig& config) {
  BusAnalysis a = analyse_once(set, config);
  if (config.what_if) a.what_if = what_if(set, config);
  return a;
}

}  // namespace canhil::timing
