// Each expectation judged on what its run recorded (record.hpp): the
// verdict, what was measured, and on failure when and where to look.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "canhil/base/text_format.hpp"
#include "record.hpp"

namespace canhil::verdict::detail {
namespace {

Verdict pass(Verdict v, std::string measured) {
  v.passed = true;
  v.measured = std::move(measured);
  return v;
}

Verdict fail(Verdict v, std::string measured, std::string why, const Record& r, std::optional<double> at = {}) {
  v.passed = false;
  v.measured = std::move(measured);
  v.message = std::move(why) + "; see " + r.where + (at ? format_text(" at t=%.3f s", *at) : std::string());
  return v;
}

// Samples come every elementary cycle (10 ms) and at each event: the one
// judged "at" a time is at most this much later.
constexpr double kSampleSlack_s = 0.0105;

double distance(const Sample& a, double x, double y) { return std::hypot(a.x - x, a.y - y); }

// A robot's speed at sample i: over the last 20 ms or more (the samples come
// every elementary cycle, and at each event between).
double speed_at(const std::vector<Sample>& s, std::size_t i) {
  std::size_t j = i;
  while (j > 0 && s[i].t - s[j].t < 0.02) --j;
  const double dt = s[i].t - s[j].t;
  return dt > 0 ? distance(s[i], s[j].x, s[j].y) / dt : 0;
}

Verdict ball_in_goal(Verdict v, const Expectation& x, const Record& r) {
  const bool attacks = r.attacks_positive_x[x.robot];
  const auto wanted = [&](const emulator::Goal& g) {
    if (x.goal == "opponent") return g.positive_x == attacks;
    if (x.goal == "own") return g.positive_x != attacks;
    if (x.goal == "+x") return g.positive_x;
    if (x.goal == "-x") return !g.positive_x;
    return true;
  };
  const double by = x.by_s.value_or(r.end_s);
  for (const emulator::Goal& g : r.goals) {
    if (wanted(g) && to_seconds(g.time) <= by) {
      return pass(v, format_text("goal at %.2f s in the %s goal", to_seconds(g.time), g.positive_x ? "+x" : "-x"));
    }
  }
  const Sample ball = r.ball.empty() ? Sample{} : r.ball.back();
  std::string why = format_text("no goal in the %s goal by %.2f s; the ball ended at (%.2f, %.2f)", x.goal.c_str(), by,
                                ball.x, ball.y);
  if (by > r.end_s) why += format_text(" (the run ended at %.2f s)", r.end_s);
  for (const emulator::Goal& g : r.goals) {
    why += format_text("; a goal at %.2f s in the %s goal", to_seconds(g.time), g.positive_x ? "+x" : "-x");
  }
  return fail(v, format_text("no goal by %.2f s", by), why, r, std::min(by, r.end_s));
}

Verdict robot_near(Verdict v, const Expectation& x, const Record& r) {
  const std::vector<Sample>& robot = r.robots[x.robot];
  const double by = x.by_s.value_or(r.end_s);
  const char* what = x.near_ball ? "the ball" : "the point";
  double closest = INFINITY, closest_at = 0;
  for (std::size_t i = 0; i < robot.size(); ++i) {
    if (robot[i].t < x.from_s || robot[i].t > by) continue;
    const double d =
        x.near_ball ? distance(robot[i], r.ball[i].x, r.ball[i].y) : distance(robot[i], x.point[0], x.point[1]);
    if (d <= x.within_m) return pass(v, format_text("%.2f m from %s at %.2f s", d, what, robot[i].t));
    if (d < closest) {
      closest = d;
      closest_at = robot[i].t;
    }
  }
  return fail(
      v, format_text("closest %.2f m at %.2f s", closest, closest_at),
      format_text("robot %zu never came within %.2f m of %s between %.2f s and %.2f s; closest %.2f m at %.2f s",
                  x.robot, x.within_m, what, x.from_s, by, closest, closest_at),
      r, closest_at);
}

Verdict speed_below(Verdict v, const Expectation& x, const TestFile& test, const Record& r) {
  const double from = x.after_s ? *x.after_s : test.event(x.after)->at_s;
  const std::string since =
      x.after_s ? format_text("%.2f s", from) : "'" + x.after + "' (" + format_text("%.2f s", from) + ")";
  const std::vector<Sample>& s = r.robots[x.robot];
  const double hold = x.hold_ms / 1000;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i].t < from || speed_at(s, i) >= x.speed_m_s) continue;
    std::size_t k = i;
    while (k + 1 < s.size() && s[k + 1].t <= s[i].t + hold && speed_at(s, k + 1) < x.speed_m_s) ++k;
    if (k + 1 < s.size() && s[k + 1].t <= s[i].t + hold) continue;  // back above within the hold
    if (s[i].t + hold > r.end_s + 1e-9) break;                      // the run ended before the hold did
    const double after_ms = (s[i].t - from) * 1000;
    const std::string measured = format_text("below %.2f m/s %.0f ms after %s", x.speed_m_s, after_ms, since.c_str());
    if (after_ms <= x.within_ms) return pass(v, measured);
    return fail(v, measured,
                format_text("robot %zu took %.0f ms to go below %.2f m/s after %s, more than %.0f ms", x.robot,
                            after_ms, x.speed_m_s, since.c_str(), x.within_ms),
                r, from + x.within_ms / 1000);
  }
  const double limit = from + x.within_ms / 1000;
  double at_limit = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i].t <= limit) at_limit = speed_at(s, i);
  }
  return fail(v, format_text("%.2f m/s %.0f ms after %s", at_limit, x.within_ms, since.c_str()),
              format_text("robot %zu never stayed below %.2f m/s for %.0f ms after %s; %.2f m/s at %.2f s", x.robot,
                          x.speed_m_s, x.hold_ms, since.c_str(), at_limit, std::min(limit, r.end_s)),
              r, std::min(limit, r.end_s));
}

// A capture that cannot show timing fails every bus expectation on it: a
// team's CI must not pass on a bus that carried nothing.
std::optional<Verdict> broken_capture(const Verdict& v, const timing::TimingReport& bus, const Record& r) {
  if (bus.capture_ok()) return std::nullopt;
  return fail(v, "no timing", "the bus cannot be judged: " + bus.capture_problems.front().second, r);
}

Verdict ftt_violations(Verdict v, const Expectation& x, const Record& r) {
  const timing::TimingReport& bus = r.bus[x.robot];
  if (auto broken = broken_capture(v, bus, r)) return *broken;
  std::uint64_t count = bus.violation_count;
  if (!x.message.empty()) {
    const auto m = std::find_if(bus.messages.begin(), bus.messages.end(),
                                [&](const timing::MessageTiming& t) { return t.name == x.message; });
    if (m == bus.messages.end()) {
      return fail(v, "no such message", "the message set has no message " + x.message + " (`canhil frames list`)", r);
    }
    count = 0;
    for (const auto& [kind, n] : m->violations) count += n;
  }
  const std::string whose = x.message.empty() ? std::string() : " of " + x.message;
  const std::string measured =
      format_text("%llu violation(s)%s", static_cast<unsigned long long>(count), whose.c_str());
  if (count <= x.at_most) return pass(v, measured);
  for (const timing::Violation& first : bus.violations) {
    if (!x.message.empty() && first.message != x.message) continue;
    return fail(v, measured,
                format_text("%llu FTT violation(s)%s on %s, at most %llu allowed; the first at %.6f s: %s %s, %s",
                            static_cast<unsigned long long>(count), whose.c_str(), r.interfaces[x.robot].c_str(),
                            static_cast<unsigned long long>(x.at_most), to_seconds(first.time), first.message.c_str(),
                            timing::kind_name(first.kind), first.detail.c_str()),
                r, to_seconds(first.time));
  }
  return fail(v, measured,
              format_text("%llu FTT violation(s)%s, at most %llu allowed", static_cast<unsigned long long>(count),
                          whose.c_str(), static_cast<unsigned long long>(x.at_most)),
              r);
}

Verdict error_frames(Verdict v, const Expectation& x, const Record& r) {
  if (auto broken = broken_capture(v, r.bus[x.robot], r)) return *broken;
  const std::uint64_t n = r.bus[x.robot].error_frames;
  const std::string measured = format_text("%llu error frame(s)", static_cast<unsigned long long>(n));
  if (n <= x.at_most) return pass(v, measured);
  return fail(v, measured,
              format_text("%llu error frames on %s, at most %llu allowed", static_cast<unsigned long long>(n),
                          r.interfaces[x.robot].c_str(), static_cast<unsigned long long>(x.at_most)),
              r);
}

Verdict jitter(Verdict v, const Expectation& x, const Record& r) {
  const timing::TimingReport& bus = r.bus[x.robot];
  if (auto broken = broken_capture(v, bus, r)) return *broken;
  for (const timing::MessageTiming& m : bus.messages) {
    if (m.name != x.message) continue;
    if (m.kind == frames::FttKind::kAsync) {
      return fail(v, "no period",
                  m.name +
                      " is sporadic: it has a minimum gap, not a period, so no jitter; judge it with "
                      "ftt_violations_at_most (too soon, outside the asynchronous window)",
                  r);
    }
    if (m.count < 2)
      return fail(v, "too few frames",
                  format_text("%s came %llu time(s)", m.name.c_str(), static_cast<unsigned long long>(m.count)), r);
    const double p99 = to_seconds(m.p99) * 1000;
    const std::string measured = format_text("p99 %.3f ms over %llu frames of %s", p99,
                                             static_cast<unsigned long long>(m.count), m.name.c_str());
    if (p99 <= x.bound_ms) return pass(v, measured);
    return fail(
        v, measured,
        format_text("%s's jitter p99 is %.3f ms, more than %.3f ms (its worst interval %.3f ms, period %.3f ms)",
                    m.name.c_str(), p99, x.bound_ms, to_seconds(m.max) * 1000, to_seconds(m.spec) * 1000),
        r);
  }
  return fail(v, "no such message", "the message set has no message " + x.message + " (`canhil frames list`)", r);
}

Verdict handler_latency(Verdict v, const Expectation& x, const Record& r) {
  std::vector<Nanos> l = x.robot < r.latencies.size() ? r.latencies[x.robot] : std::vector<Nanos>{};
  if (l.empty()) {
    return fail(v, "not measured",
                "the reference handler measured no latency (a team's own handler, in its own process, is measured "
                "by `canhil timing` on its bus)",
                r);
  }
  const std::size_t k =
      std::min(l.size() - 1, static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(l.size()))) - 1);
  std::nth_element(l.begin(), l.begin() + static_cast<std::ptrdiff_t>(k), l.end());
  const double p99 = to_seconds(l[k]) * 1000;
  const std::string measured = format_text("p99 %.3f ms over %zu updates", p99, l.size());
  if (p99 <= x.bound_ms) return pass(v, measured);
  return fail(v, measured,
              format_text("the handler's receive-to-RTDB latency p99 is %.3f ms, more than %.3f ms", p99, x.bound_ms),
              r);
}

Verdict within_bounds(Verdict v, const Expectation& x, const Record& r) {
  if (!r.schedulable) {
    return fail(v, "not schedulable", "the message set is not schedulable (`canhil timing --analyse`):\n" + r.analysis,
                r);
  }
  if (auto broken = broken_capture(v, r.bus[x.robot], r)) return *broken;
  const timing::BoundReport& b = r.bounds[x.robot];
  const std::string measured = format_text("schedulable; %zu observation(s), %llu outside their bounds",
                                           b.observations.size(), static_cast<unsigned long long>(b.violation_count));
  if (b.ok()) return pass(v, measured);
  const timing::BoundViolation& first = b.violations.front();
  return fail(
      v, measured,
      format_text("%s's %s of %.3f ms is outside [%.3f, %.3f] ms at %.6f s (`canhil timing --analyse TRACE`)",
                  first.message.c_str(), timing::bounded_name(first.quantity), to_seconds(first.observed) * 1000,
                  to_seconds(first.low) * 1000, to_seconds(first.high) * 1000, to_seconds(first.time)),
      r, to_seconds(first.time));
}

Verdict rtdb_quantity(Verdict v, const Expectation& x, std::size_t index, const Record& r) {
  if (const auto e = r.rtdb_errors.find(index); e != r.rtdb_errors.end()) {
    return fail(v, "not read", x.item + "." + x.quantity + ": " + e->second, r);
  }
  const auto found = r.rtdb.find(index);
  const std::string what = x.item + "." + x.quantity;
  if (found == r.rtdb.end() || found->second.empty()) {
    return fail(v, "never written", what + format_text(" was never written in robot %zu's database", x.robot), r);
  }
  const auto bad = [&](const RtdbSample& s) {
    return s.value < x.low || s.value > x.high || (x.age_ms && s.age_ms > *x.age_ms);
  };
  const auto say = [&](const RtdbSample& s) {
    return format_text("%.4g at %.2f s, %d ms old", s.value, s.t, s.age_ms);
  };
  const std::string bounds = format_text("[%g, %g]", x.low, x.high) +
                             (x.age_ms ? format_text(", at most %.0f ms old", *x.age_ms) : std::string());
  if (x.at_s) {
    for (const RtdbSample& s : found->second) {
      if (s.t + 1e-9 < *x.at_s) continue;
      if (s.t > *x.at_s + kSampleSlack_s) {
        return fail(v, "not there",
                    format_text("%s had no value yet at %.2f s (first written at %.2f s)", what.c_str(), *x.at_s,
                                found->second.front().t),
                    r, *x.at_s);
      }
      if (!bad(s)) return pass(v, what + " " + say(s));
      return fail(v, what + " " + say(s), what + " is " + say(s) + ", outside " + bounds, r, s.t);
    }
    return fail(v, "not there",
                format_text("%s had no value at %.2f s (the run ended at %.2f s)", what.c_str(), *x.at_s, r.end_s), r);
  }
  std::size_t n = 0;
  for (const RtdbSample& s : found->second) {
    if (s.t + 1e-9 < x.from_s) continue;
    ++n;
    if (bad(s)) {
      return fail(v, what + " " + say(s),
                  what + format_text(" left %s from %.2f s on: ", bounds.c_str(), x.from_s) + say(s), r, s.t);
    }
  }
  if (n == 0) return fail(v, "not there", what + format_text(" had no value from %.2f s on", x.from_s), r);
  return pass(v, format_text("%s inside %s in all %zu samples from %.2f s", what.c_str(), bounds.c_str(), n, x.from_s));
}

Verdict processes(Verdict v, const Expectation& x, const Record& r) {
  if (!r.external) {
    return fail(v, "no processes",
                "the run had none of the team's processes: processes_ok is for `canhil test --external`", r);
  }
  if (r.stuck) return fail(v, "stuck", "the run stopped " + *r.stuck, r, r.end_s);  // "at t = T s: why"
  for (const external::ProcessEnd& e : r.ends) {
    const std::string how = format_text("%s %d", e.signalled ? "signal" : "exit status", e.code);
    const std::string who = format_text("`%s` (agent %d, pid %d)", e.command.c_str(), e.agent, static_cast<int>(e.pid));
    if (e.during_run) {
      return fail(
          v, who + " ended",
          format_text("%s ended at t = %.3f s, before the run's end: ", who.c_str(), to_seconds(*e.during_run)) + how,
          r, to_seconds(*e.during_run));
    }
    if (!x.exit_codes.empty() &&
        (e.signalled || std::find(x.exit_codes.begin(), x.exit_codes.end(), e.code) == x.exit_codes.end())) {
      return fail(v, who + " " + how, who + " ended with " + how + " when the run's end stopped it (SIGINT)", r);
    }
  }
  std::string codes;
  for (const external::ProcessEnd& e : r.ends) codes += (codes.empty() ? "" : ", ") + std::to_string(e.code);
  return pass(v, format_text("%zu process(es) answered to the end; stopped with %s", r.started,
                             codes.empty() ? "nothing reported" : codes.c_str()));
}

}  // namespace

Verdict judge(const Expectation& x, const TestFile& test, const Record& record) {
  Verdict v;
  v.name = x.name;
  v.check = check_key(x.check);
  v.line = x.line;
  switch (x.check) {
    case Check::kBallInGoal:
      return ball_in_goal(v, x, record);
    case Check::kRobotNear:
      return robot_near(v, x, record);
    case Check::kSpeedBelow:
      return speed_below(v, x, test, record);
    case Check::kFttViolations:
      return ftt_violations(v, x, record);
    case Check::kErrorFrames:
      return error_frames(v, x, record);
    case Check::kJitter:
      return jitter(v, x, record);
    case Check::kHandlerLatency:
      return handler_latency(v, x, record);
    case Check::kWithinBounds:
      return within_bounds(v, x, record);
    case Check::kRtdb:
      return rtdb_quantity(v, x, static_cast<std::size_t>(&x - test.expectations.data()), record);
    case Check::kProcesses:
      return processes(v, x, record);
  }
  return v;
}

}  // namespace canhil::verdict::detail
