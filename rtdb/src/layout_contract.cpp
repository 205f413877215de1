// canhil's side of the layouts: the quantities it gives and takes per item
// (the contract, fixed names) and the units a description may store them in.
#include <algorithm>
#include <array>
#include <cmath>

#include "canhil/base/spelling.hpp"
#include "layout_internal.hpp"

namespace canhil::rtdb {
namespace {

constexpr std::array<UnitInfo, 22> kUnits{{
    {"1", Dimension::kNone, 1, 0},
    {"m", Dimension::kLength, 1, 0},
    {"cm", Dimension::kLength, 100, 0},
    {"mm", Dimension::kLength, 1000, 0},
    {"rad", Dimension::kAngle, 1, 0},
    {"mrad", Dimension::kAngle, 1000, 0},
    {"deg", Dimension::kAngle, 180, -1},
    {"cdeg", Dimension::kAngle, 18000, -1},
    {"m/s", Dimension::kSpeed, 1, 0},
    {"cm/s", Dimension::kSpeed, 100, 0},
    {"mm/s", Dimension::kSpeed, 1000, 0},
    {"rad/s", Dimension::kAngularSpeed, 1, 0},
    {"mrad/s", Dimension::kAngularSpeed, 1000, 0},
    {"deg/s", Dimension::kAngularSpeed, 180, -1},
    {"V", Dimension::kVoltage, 1, 0},
    {"dV", Dimension::kVoltage, 10, 0},
    {"cV", Dimension::kVoltage, 100, 0},
    {"mV", Dimension::kVoltage, 1000, 0},
    {"s", Dimension::kTime, 1, 0},
    {"ms", Dimension::kTime, 1000, 0},
    {"us", Dimension::kTime, 1e6, 0},
    {"ns", Dimension::kTime, 1e9, 0},
}};

constexpr std::array<std::string_view, 20> kGameStates{
    "stop",          "start",          "halt",          "ready",          "drop_ball",  "our_kickoff",  "their_kickoff",
    "our_freekick",  "their_freekick", "our_goalkick",  "their_goalkick", "our_corner", "their_corner", "our_throwin",
    "their_throwin", "our_penalty",    "their_penalty", "our_goal",       "their_goal", "parking"};
constexpr std::array<std::string_view, 20> kRoles{
    "none",        "stop",           "goalie",  "striker",       "midfielder", "test", "replacer", "barrier",
    "cursor",      "penalty",        "parking", "tour",          "a",          "b",    "c",        "receiver",
    "receiver_fp", "kick_calibrate", "taxi",    "goalie_penalty"};
constexpr std::array<std::string_view, 4> kColors{"blue", "yellow", "magenta", "cyan"};
constexpr std::array<std::string_view, 2> kEnds{"positive_x", "negative_x"};

constexpr QuantityInfo number(std::string_view item, std::string_view name, std::string_view unit,
                              std::string_view meaning, bool per_agent = false) {
  return {item, name, QuantityKind::kNumber, unit, per_agent, false, {}, meaning};
}
constexpr QuantityInfo boolean(std::string_view item, std::string_view name, std::string_view meaning,
                               bool per_agent = false) {
  return {item, name, QuantityKind::kBool, "1", per_agent, false, {}, meaning};
}
constexpr QuantityInfo points(std::string_view item, std::string_view name, std::string_view meaning) {
  return {item, name, QuantityKind::kPoints, "m", false, false, {}, meaning};
}
constexpr QuantityInfo count(std::string_view item, std::string_view name, std::string_view meaning) {
  return {item, name, QuantityKind::kCount, "1", false, false, {}, meaning};
}
template <std::size_t N>
constexpr QuantityInfo enumerated(std::string_view item, std::string_view name,
                                  const std::array<std::string_view, N>& names, std::string_view meaning,
                                  bool per_agent) {
  return {item, name, QuantityKind::kEnum, "1", per_agent, false, names, meaning};
}

// Items in the order of docs/layouts.md; the quantities of one item together.
constexpr std::array<QuantityInfo, 53> kContract{{
    points("VISION_INFO", "obstacles", "obstacle points, robot frame (x right, y forward)"),
    count("VISION_INFO", "obstacles.count", "obstacle points written (at most the capacity)"),
    points("VISION_INFO", "lines", "white field-line points, robot frame"),
    count("VISION_INFO", "lines.count", "line points written (at most the capacity)"),
    points("VISION_INFO", "balls", "balls seen, projected to the ground, robot frame"),
    count("VISION_INFO", "balls.count", "balls written (at most the capacity)"),
    number("CMD_VEL", "vx", "m/s", "velocity command, robot frame, right"),
    number("CMD_VEL", "vy", "m/s", "velocity command, robot frame, forward"),
    number("CMD_VEL", "va", "rad/s", "angular velocity command, counter-clockwise"),
    boolean("CMD_VEL", "small_adjustment", "gentle acceleration asked"),
    number("LAST_CMD_VEL", "vx", "m/s", "the velocity the handler last sent, right"),
    number("LAST_CMD_VEL", "vy", "m/s", "... forward"),
    number("LAST_CMD_VEL", "va", "rad/s", "... counter-clockwise"),
    boolean("LAST_CMD_VEL", "small_adjustment", "... gentle acceleration"),
    number("CMD_KICKER", "kick", "1", "M7's kick byte: bit 7 low kick, bits 0-6 power; 0 = none"),
    number("CMD_KICKER", "eng_level_high", "1", "barrier engage threshold, high"),
    number("CMD_KICKER", "eng_level_low", "1", "barrier engage threshold, low"),
    number("CMD_GRABBER", "grabber", "1", "grabber command, fraction 0..1"),
    number("CMD_POS", "x", "m", "odometry position"),
    number("CMD_POS", "y", "m", "odometry position"),
    number("CMD_POS", "heading", "rad", "odometry heading, counter-clockwise"),
    number("CMD_POS", "dx", "m", "change of position since the previous write (deltas_frame)"),
    number("CMD_POS", "dy", "m", "change of position since the previous write (deltas_frame)"),
    number("CMD_POS", "dheading", "rad", "change of heading since the previous write, counter-clockwise"),
    number("CMD_INFO", "v_logic", "V", "logic battery"),
    number("CMD_INFO", "v_power12", "V", "12 V power battery"),
    number("CMD_INFO", "v_power24", "V", "24 V power battery"),
    number("CMD_INFO", "v_kicker", "V", "kicker capacitor"),
    boolean("CMD_INFO", "just_kicked", "the kicker fired"),
    {"CMD_IMU",
     "heading",
     QuantityKind::kNumber,
     "deg",
     false,
     true,
     {},
     "compass: degrees clockwise from magnetic north"},
    number("CMD_IMU", "raw", "1", "the compass's raw count"),
    number("CMD_HWERRORS", "bad_frames", "1", "bad frames the nodes counted (M10)"),
    number("CMD_HWERRORS", "alive", "1", "alive bitmap (M10)"),
    number("CMD_HWERRORS", "node_state", "1", "node state (M10)"),
    number("CMD_HWERRORS", "wrong_length", "1", "frames of a wrong length the handler saw"),
    number("CMD_HWERRORS", "out_of_range", "1", "frames with out-of-range values"),
    number("CMD_HWERRORS", "unknown_id", "1", "frames with unknown ids"),
    number("CMD_HWERRORS", "missed_tms", "1", "trigger messages missed"),
    number("CMD_HWERRORS", "send_failed", "1", "frames the handler failed to send"),
    boolean("CMD_GRABBER_INFO", "ball_engaged", "the barrier sees the ball"),
    number("CMD_GRABBER_INFO", "grabber", "1", "grabber state, fraction 0..1"),
    enumerated("COACH_INFO", "game_state", kGameStates, "the referee's state", false),
    boolean("COACH_INFO", "running", "the robot may play", true),
    boolean("COACH_INFO", "role_auto", "the robot chooses its role", true),
    enumerated("COACH_INFO", "role", kRoles, "the role the coach gives", true),
    enumerated("COACH_INFO", "team_color", kColors, "the team's colour", true),
    enumerated("COACH_INFO", "attacks", kEnds,
               "the goal the robot's team attacks (this half): the one at world +x or at -x", true),
    number("COACH_INFO", "relocations", "1",
           "times canhil moved the robot (referee, viewer, control), each counted a relocation delay after the "
           "move: a new value says \"find yourself again\"",
           true),
    number("CMD_SETPOSE", "x", "m", "pose to set"),
    number("CMD_SETPOSE", "y", "m", "pose to set"),
    number("CMD_SETPOSE", "heading", "rad", "pose to set, counter-clockwise"),
    number("CMD_SETPOSE", "command", "1", "0 set the pose, 1 reset to zero"),
    boolean("CMD_SETPOSE", "pending", "a request waits for the handler"),
    // FORMATION_INFO: canhil's coach writes it, all constants or zeros (no quantity).
}};
static_assert(kContract.back().item == "CMD_SETPOSE" && kContract.back().name == "pending", "one entry each");

constexpr std::array<std::string_view, 13> kContractItems{
    "VISION_INFO", "CMD_VEL",      "LAST_CMD_VEL",     "CMD_KICKER", "CMD_GRABBER",    "CMD_POS",    "CMD_INFO",
    "CMD_IMU",     "CMD_HWERRORS", "CMD_GRABBER_INFO", "COACH_INFO", "FORMATION_INFO", "CMD_SETPOSE"};

}  // namespace

std::span<const QuantityInfo> contract() noexcept { return kContract; }

std::span<const QuantityInfo> quantities_of(std::string_view item) noexcept {
  const auto all = contract();
  const auto first = std::find_if(all.begin(), all.end(), [&](const QuantityInfo& q) { return q.item == item; });
  const auto last = std::find_if(first, all.end(), [&](const QuantityInfo& q) { return q.item != item; });
  return {first, last};
}

const QuantityInfo* find_quantity(std::string_view item, std::string_view quantity) noexcept {
  for (const QuantityInfo& q : quantities_of(item)) {
    if (q.name == quantity) return &q;
  }
  return nullptr;
}

bool is_contract_item(std::string_view item) noexcept {
  return std::find(kContractItems.begin(), kContractItems.end(), item) != kContractItems.end();
}

std::span<const std::string_view> contract_items() noexcept { return kContractItems; }

const UnitInfo* find_unit(std::string_view name) noexcept {
  for (const UnitInfo& u : kUnits) {
    if (u.name == name) return &u;
  }
  return nullptr;
}

std::span<const UnitInfo> units() noexcept { return kUnits; }

std::string_view dimension_name(Dimension d) noexcept {
  switch (d) {
    case Dimension::kNone:
      return "dimensionless";
    case Dimension::kLength:
      return "a length";
    case Dimension::kAngle:
      return "an angle";
    case Dimension::kSpeed:
      return "a speed";
    case Dimension::kAngularSpeed:
      return "an angular speed";
    case Dimension::kVoltage:
      return "a voltage";
    case Dimension::kTime:
      return "a time";
  }
  return "?";
}

std::string units_of(Dimension d) {
  std::string out;
  for (const UnitInfo& u : kUnits) {
    if (u.dimension == d) out += (out.empty() ? "" : ", ") + std::string(u.name);
  }
  return out;
}

Dimension dimension_of(const QuantityInfo& q) noexcept {
  const UnitInfo* u = find_unit(q.si_unit);
  return u == nullptr ? Dimension::kNone : u->dimension;
}

double units_per(const UnitInfo& stored, const UnitInfo& given) noexcept {
  const double ratio = stored.factor / given.factor;
  const int p = stored.pi_power - given.pi_power;
  return p == 0 ? ratio : ratio * std::pow(3.14159265358979323846, p);
}

std::string did_you_mean(std::string_view word, std::span<const std::string_view> candidates) {
  const std::string_view best = nearest_word(word, candidates);
  return best.empty() ? "" : " Did you mean " + std::string(best) + "?";
}

}  // namespace canhil::rtdb
