#include "canhil/can_nodes/fault.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

#include "canhil/base/setup_error.hpp"
#include "canhil/frames/wire.hpp"

namespace canhil::can_nodes {
namespace {

constexpr std::uint32_t kNoId = 0xFFFFFFFF;
constexpr const char* kSyntax =
    "; a fault is KIND:TARGET[:ARGS][@SECONDS[+SECONDS]] with KIND drop, delay, corrupt, duplicate, silence, error, "
    "battery or, on a timed wire, ber, noack, stuck, babble, cut, busoff, e.g. drop:M4_1:0.5, delay:M3_1:3, "
    "corrupt:M1:2, duplicate:M9:2, silence:Motor2:5, error:*:0.01, battery:power24:2, ber:*:1e-5, "
    "busoff:laptop@3 (see docs/faults.md)";

[[noreturn]] void bad(std::string_view text, const std::string& what) {
  throw SetupError("fault '" + std::string(text) + "': " + what + kSyntax);
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= s.size(); ++i) {
    if (i == s.size() || s[i] == sep) {
      out.push_back(s.substr(start, i - start));
      start = i + 1;
    }
  }
  return out;
}

double number(std::string_view text, std::string_view field, const std::string& name) {
  double v = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), v);
  if (ec != std::errc{} || end != field.data() + field.size() || !std::isfinite(v)) {
    bad(text, name + " must be a number, got '" + std::string(field) + "'");
  }
  return v;
}

// A time into the run, in seconds: 0 up to a year (a few hundred years fit the
// nanosecond count; more would overflow it).
constexpr double kMostSeconds = 365.0 * 24 * 3600;

Nanos seconds_into_run(std::string_view text, std::string_view field, const std::string& name) {
  const double s = number(text, field, name);
  if (s < 0 || s > kMostSeconds) {
    bad(text, name + " must be 0 to " + std::to_string(static_cast<long>(kMostSeconds)) + " s (a year), got " +
                  std::string(field));
  }
  return from_seconds(s);
}

double probability(std::string_view text, std::string_view field) {
  const double p = number(text, field, "the probability");
  if (p < 0 || p > 1) bad(text, "the probability must be between 0 and 1, got " + std::string(field));
  return p;
}

// A rule's node target against a node's name, spaces written as underscores; no allocation.
bool names_node(std::string_view target, std::string_view node) {
  if (target.size() != node.size()) return false;
  for (std::size_t k = 0; k < node.size(); ++k) {
    if (target[k] != (node[k] == ' ' ? '_' : node[k])) return false;
  }
  return true;
}

}  // namespace

std::string fault_node_name(std::string_view node) {
  std::string out(node);
  std::replace(out.begin(), out.end(), ' ', '_');
  return out;
}

FaultRule parse_fault(std::string_view text) {
  FaultRule rule;
  rule.text = std::string(text);
  std::string_view body = text;
  if (const auto at = body.find('@'); at != std::string_view::npos) {
    std::string_view when = body.substr(at + 1);
    if (const auto plus = when.find('+'); plus != std::string_view::npos) {
      const Nanos lasting = seconds_into_run(text, when.substr(plus + 1), "the duration after +");
      if (lasting <= Nanos{0}) bad(text, "the duration after + must be above 0 s");
      when = when.substr(0, plus);
      rule.from = seconds_into_run(text, when, "the start time after @");
      rule.until = rule.from + lasting;
    } else {
      rule.from = seconds_into_run(text, when, "the start time after @");
    }
    body = body.substr(0, at);
  }
  const auto parts = split(body, ':');
  if (parts.size() < 2 || parts[1].empty()) bad(text, "a kind and a target are needed");
  const std::string_view kind = parts[0];
  rule.target = std::string(parts[1]);
  const auto args = parts.size() - 2;
  auto arg = [&](std::size_t k) { return parts[2 + k]; };
  if (kind == "drop") {
    rule.kind = FaultKind::kDrop;
    if (args > 1) bad(text, "drop takes at most a probability");
    if (args == 1) rule.probability = probability(text, arg(0));
  } else if (kind == "delay") {
    rule.kind = FaultKind::kDelay;
    if (args < 1 || args > 2) bad(text, "delay takes milliseconds and optionally a probability");
    const double ms = number(text, arg(0), "the delay");
    if (ms <= 0 || ms > 10'000) bad(text, "the delay must be above 0 and at most 10000 ms");
    rule.delay = from_seconds(ms / 1000);
    if (args == 2) rule.probability = probability(text, arg(1));
  } else if (kind == "corrupt") {
    rule.kind = FaultKind::kCorrupt;
    if (args < 1 || args > 2) bad(text, "corrupt takes a byte number (0-7) and optionally a probability");
    const double b = number(text, arg(0), "the byte");
    if (b < 0 || b > 7 || b != std::floor(b)) bad(text, "the byte must be a whole number 0-7");
    rule.byte = static_cast<int>(b);
    if (args == 2) rule.probability = probability(text, arg(1));
  } else if (kind == "duplicate") {
    rule.kind = FaultKind::kDuplicate;
    if (args > 2) bad(text, "duplicate takes optionally a number of copies and a probability");
    if (args >= 1) {
      const double c = number(text, arg(0), "the number of copies");
      if (c < 1 || c > 16 || c != std::floor(c)) bad(text, "the copies must be a whole number 1-16");
      rule.copies = static_cast<int>(c);
    }
    if (args == 2) rule.probability = probability(text, arg(1));
  } else if (kind == "silence") {
    rule.kind = FaultKind::kSilence;
    if (args != 1) bad(text, "silence takes the time in seconds it starts");
    rule.from = std::max(rule.from, seconds_into_run(text, arg(0), "the time"));
  } else if (kind == "error") {
    rule.kind = FaultKind::kErrorFrame;
    if (args > 1) bad(text, "error takes at most a probability");
    if (args == 1) rule.probability = probability(text, arg(0));
  } else if (kind == "battery") {
    rule.kind = FaultKind::kBattery;
    if (rule.target != "*" &&
        std::find(std::begin(kBatteryPacks), std::end(kBatteryPacks), rule.target) == std::end(kBatteryPacks)) {
      bad(text, "the battery's target is a pack: logic, power12, power24 or *");
    }
    if (args != 1) bad(text, "battery takes the pack and the percent of a full pack it loses per second");
    const double percent = number(text, arg(0), "the percent per second");
    if (percent <= 0 || percent > 100) bad(text, "the percent per second must be above 0 and at most 100");
    rule.drain_per_s = percent / 100;
  } else if (kind == "ber") {
    rule.kind = FaultKind::kBitErrors;
    if (rule.target != "*") bad(text, "ber acts on the whole bus: its target is *");
    if (args != 1) bad(text, "ber takes the probability of each bit flipping");
    rule.bit_error_rate = probability(text, arg(0));
  } else if (kind == "noack" || kind == "stuck" || kind == "cut" || kind == "busoff") {
    rule.kind = kind == "noack"   ? FaultKind::kNoAck
                : kind == "stuck" ? FaultKind::kStuckDominant
                : kind == "cut"   ? FaultKind::kCut
                                  : FaultKind::kBusOff;
    if (args != 0) bad(text, std::string(kind) + " takes no arguments");
    if (kind != "noack" && rule.target == "*") bad(text, std::string(kind) + " names one node, or laptop");
  } else if (kind == "babble") {
    rule.kind = FaultKind::kBabbling;
    if (rule.target == "*") bad(text, "babble names one node, or laptop");
    if (args > 1) bad(text, "babble takes at most the identifier it sends");
    if (args == 1) {
      unsigned id = 0;
      const std::string_view field = arg(0);
      const bool hex = field.size() > 2 && field[0] == '0' && (field[1] == 'x' || field[1] == 'X');
      const std::string_view digits = hex ? field.substr(2) : field;
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), id, hex ? 16 : 10);
      if (ec != std::errc{} || end != digits.data() + digits.size() || id > frames::kStandardIdMask) {
        bad(text, "the identifier must be 0 to 0x7FF, got '" + std::string(field) + "'");
      }
      rule.babble_id = id;
    }
  } else {
    bad(text, "unknown kind '" + std::string(kind) + "'");
  }
  if (rule.until != kNever && !wire_only(rule.kind)) bad(text, "only a wire rule takes a duration (@SECONDS+SECONDS)");
  return rule;
}

FaultCount& FaultCount::operator+=(const FaultCount& other) {
  matched += other.matched;
  applied += other.applied;
  active += other.active;
  on_wire = on_wire || other.on_wire;
  return *this;
}

std::string describe(const FaultCount& c) {
  char line[96];
  if (c.kind == FaultKind::kBattery) {
    std::snprintf(line, sizeof line, "drained for %.1f s", to_seconds(c.active));
  } else if (wire_only(c.kind) || c.on_wire) {
    std::snprintf(line, sizeof line, "on the wire: its counts are the controllers' (bus report)");
  } else {
    std::snprintf(line, sizeof line, "matched %8llu frames, applied to %8llu",
                  static_cast<unsigned long long>(c.matched), static_cast<unsigned long long>(c.applied));
  }
  return line;
}

FaultInjector::FaultInjector(const std::vector<FaultRule>& rules, std::shared_ptr<const frames::MessageSet> set,
                             const std::vector<std::string>& node_names, std::uint64_t seed, std::uint32_t bit_rate)
    : set_(std::move(set)), node_names_(node_names), state_(seed), bit_rate_(bit_rate) {
  for (const FaultRule& rule : rules) add_rule(rule);
}

std::uint32_t FaultInjector::target_id(const FaultRule& rule) const {
  if (rule.target == "*" || rule.kind == FaultKind::kBattery) return kNoId;
  const bool needs_node = rule.kind == FaultKind::kStuckDominant || rule.kind == FaultKind::kBabbling ||
                          rule.kind == FaultKind::kCut || rule.kind == FaultKind::kBusOff;
  if (const frames::MessageCodec* m = set_->codec().find(rule.target)) {
    if (needs_node) {
      throw SetupError("fault '" + rule.text + "': '" + rule.target +
                       "' is a message; this fault names a node or laptop");
    }
    return m->id();
  }
  if (rule.target == kLaptopTarget) return kNoId;
  const bool node = std::any_of(node_names_.begin(), node_names_.end(),
                                [&](const std::string& n) { return names_node(rule.target, n); });
  if (!node) {
    std::string known;
    for (const std::string& n : node_names_) {
      known += ' ';
      known += fault_node_name(n);
    }
    throw SetupError("fault '" + rule.text + "': '" + rule.target +
                     "' is neither a message of the message set nor a node; the nodes are" + known +
                     ", and laptop (the handler)");
  }
  return kNoId;
}

void FaultInjector::add_rule(const FaultRule& rule) {
  const std::uint32_t id = target_id(rule);  // before the lock: it may throw
  const std::lock_guard lock(mutex_);
  rules_.push_back(rule);
  rule_ids_.push_back(id);
  counts_.push_back({rule.text, rule.kind, 0, 0, Nanos{0}});
  rule_count_.store(rules_.size(), std::memory_order_release);
}

std::vector<FaultCount> FaultInjector::counts() const {
  const std::lock_guard lock(mutex_);
  std::vector<FaultCount> counts = counts_;
  for (FaultCount& c : counts) c.on_wire = errors_on_wire_ && c.kind == FaultKind::kErrorFrame;
  return counts;
}

bool FaultInjector::matches(std::size_t k, const std::string& node, std::uint32_t id) const {
  const FaultRule& rule = rules_[k];
  // `*` is every node's frame: the laptop's only by name or by its messages.
  if (rule.target == "*") return node != kLaptopTarget;
  if (rule_ids_[k] != kNoId) return rule_ids_[k] == id;
  return names_node(rule.target, node);
}

double FaultInjector::uniform() {
  // SplitMix64: small, fast and the same everywhere.
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

FaultDecision FaultInjector::on_send(const std::string& node, const frames::CanFrame& frame, Nanos now) {
  FaultDecision d;
  if (rule_count_.load(std::memory_order_acquire) == 0) return d;
  const std::lock_guard lock(mutex_);
  for (std::size_t k = 0; k < rules_.size(); ++k) {
    const FaultRule& rule = rules_[k];
    if (rule.kind == FaultKind::kBattery || wire_only(rule.kind) ||
        (errors_on_wire_ && rule.kind == FaultKind::kErrorFrame) || now - start_ < rule.from ||
        !matches(k, node, frame.id)) {
      continue;  // the wire does these (wire_faults.hpp)
    }
    ++counts_[k].matched;
    // Every matching rule draws once, so one rule's outcome never shifts another's draws.
    const double draw = uniform();
    if (rule.kind != FaultKind::kSilence && draw >= rule.probability) continue;
    ++counts_[k].applied;
    switch (rule.kind) {
      case FaultKind::kDrop:
      case FaultKind::kSilence:
        d.drop = true;
        break;
      case FaultKind::kDelay:
        d.delay = std::max(d.delay, rule.delay);
        break;
      case FaultKind::kCorrupt:
        d.corrupt_byte = rule.byte;
        d.corrupt_mask = 0xFF;
        break;
      case FaultKind::kDuplicate:
        d.duplicates += rule.copies;
        break;
      case FaultKind::kErrorFrame:
        // The error is taken to hit the frame's last bits: the whole frame and
        // the error frame pass before the controller's retransmission starts.
        d.error_frame = true;
        d.delay =
            std::max(d.delay, frames::bits_to_time(frames::frame_bits(frame) + frames::kErrorFrameBits, bit_rate_));
        break;
      default:  // battery and the wire's rules: not here
        break;
    }
  }
  return d;
}

std::array<double, 3> FaultInjector::battery_drain_until(Nanos now) {
  std::array<double, 3> drain{};
  // drained_until_ is this thread's alone (the physics'): kept current even
  // without rules, so a rule added later drains from then on, not from the start.
  const Nanos since = drained_until_;
  drained_until_ = std::max(drained_until_, now);
  if (rule_count_.load(std::memory_order_acquire) == 0) return drain;
  const std::lock_guard lock(mutex_);
  for (std::size_t k = 0; k < rules_.size(); ++k) {
    const FaultRule& rule = rules_[k];
    if (rule.kind != FaultKind::kBattery) continue;
    const Nanos from = std::max(since, start_ + rule.from);
    if (now <= from) continue;
    counts_[k].active += now - from;
    const double amount = rule.drain_per_s * to_seconds(now - from);
    for (std::size_t pack = 0; pack < drain.size(); ++pack) {
      if (rule.target == "*" || rule.target == kBatteryPacks[pack]) drain[pack] += amount;
    }
  }
  return drain;
}

}  // namespace canhil::can_nodes
