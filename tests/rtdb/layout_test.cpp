// The shipped layouts, byte for byte: every field of cambada.toml checked
// against C structs declared from the published CAMBADA facts
// (cambada_facts.hpp), every field of canhil.toml against canhil's own
// header; every quantity of both round-trips. (layout_bytes_test.cpp reads
// what the layouts write back through those structs.)
#include "canhil/rtdb/layout.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "canhil/rtdb/cambada_types.h"
#include "rtdb/cambada_facts.hpp"

// canhil's own header, as its RTDB configuration uses it.
static_assert(sizeof(VisionInfo) == 4852 && sizeof(CMD_Grabber_Info) == 2 && sizeof(CMD_SetPose) == 16);

namespace canhil::rtdb {
namespace {

// What a C struct says of one field: offset, scalar size, elements, stride, components.
struct Expect {
  std::size_t offset, scalar, count, stride, components;
  bool operator==(const Expect&) const = default;
};
using Fields = std::map<std::string, Expect>;
struct ItemExpect {
  std::size_t size;
  Fields fields;
};

template <class T>
using Bare = std::remove_cvref_t<T>;
#define MEMBER(T, m) (std::declval<T&>().m)
// A scalar member.
#define SCALAR(T, m) \
  Expect { offsetof(T, m), sizeof(MEMBER(T, m)), 1, sizeof(MEMBER(T, m)), 1 }
// An array of scalars, or of (x, y) Vecs (components 2).
#define ARRAY(T, m, elem)                                                                      \
  Expect {                                                                                     \
    offsetof(T, m), sizeof(MEMBER(T, m[0] elem)), std::extent_v<Bare<decltype(MEMBER(T, m))>>, \
        sizeof(MEMBER(T, m[0])), 1                                                             \
  }
#define VEC_ARRAY(T, m)                                                                                                \
  Expect {                                                                                                             \
    offsetof(T, m), sizeof(MEMBER(T, m[0].x)), std::extent_v<Bare<decltype(MEMBER(T, m))>>, sizeof(MEMBER(T, m[0])), 2 \
  }
// One member of each element of an array of structs.
#define OF_EACH(T, array, m, components)                                                         \
  Expect {                                                                                       \
    offsetof(T, array[0].m), sizeof(MEMBER(T, array[0].m)) / (components),                       \
        std::extent_v<Bare<decltype(MEMBER(T, array))>>, sizeof(MEMBER(T, array[0])), components \
  }

std::map<std::string, ItemExpect> cambada_structs() {
  const Fields vel{{"vx", SCALAR(facts::CMD_Vel, vx)},
                   {"vy", SCALAR(facts::CMD_Vel, vy)},
                   {"va", SCALAR(facts::CMD_Vel, va)},
                   {"smallAdjustment", SCALAR(facts::CMD_Vel, smallAdjustment)}};
  Fields hwerrors;
  for (const auto& [name, r, c] : {std::tuple{"[0][0]", 0, 0},
                                   {"[0][1]", 0, 1},
                                   {"[0][2]", 0, 2},
                                   {"[1][0]", 1, 0},
                                   {"[1][1]", 1, 1},
                                   {"[1][2]", 1, 2},
                                   {"[1][3]", 1, 3},
                                   {"[1][4]", 1, 4}}) {
    const auto at =
        offsetof(facts::CMD_HWerrors, error_count) + sizeof(unsigned short) * static_cast<std::size_t>(r * 8 + c);
    hwerrors[std::string("error_count") + name] = Expect{at, sizeof(unsigned short), 1, sizeof(unsigned short), 1};
  }
  return {
      {"VISION_INFO",
       {sizeof(facts::VisionInfo),
        {{"obstacles.nPoints", SCALAR(facts::VisionInfo, obstacles.nPoints)},
         {"obstacles.point", VEC_ARRAY(facts::VisionInfo, obstacles.point)},
         {"lines.nPoints", SCALAR(facts::VisionInfo, lines.nPoints)},
         {"lines.point", VEC_ARRAY(facts::VisionInfo, lines.point)},
         {"ball.position", OF_EACH(facts::VisionInfo, ball, position, 2)},
         {"nBalls", SCALAR(facts::VisionInfo, nBalls)}}}},
      {"CMD_VEL", {sizeof(facts::CMD_Vel), vel}},
      {"LAST_CMD_VEL", {sizeof(facts::CMD_Vel), vel}},
      {"CMD_POS",
       {sizeof(facts::CMD_Pos),
        {{"px", SCALAR(facts::CMD_Pos, px)},
         {"py", SCALAR(facts::CMD_Pos, py)},
         {"pa", SCALAR(facts::CMD_Pos, pa)},
         {"dx", SCALAR(facts::CMD_Pos, dx)},
         {"dy", SCALAR(facts::CMD_Pos, dy)},
         {"da", SCALAR(facts::CMD_Pos, da)}}}},
      {"CMD_KICKER",
       {sizeof(facts::CMD_Kicker),
        {{"power", SCALAR(facts::CMD_Kicker, power)},
         {"engLvlHigh", SCALAR(facts::CMD_Kicker, engLvlHigh)},
         {"engLvlLow", SCALAR(facts::CMD_Kicker, engLvlLow)}}}},
      {"CMD_GRABBER", {sizeof(facts::CMD_Grabber), {{"mode", SCALAR(facts::CMD_Grabber, mode)}}}},
      {"CMD_INFO",
       {sizeof(facts::CMD_Info),
        {{"Voltage_logic", SCALAR(facts::CMD_Info, Voltage_logic)},
         {"Voltage_power12", SCALAR(facts::CMD_Info, Voltage_power12)},
         {"Voltage_power24", SCALAR(facts::CMD_Info, Voltage_power24)},
         {"Kicker_voltage", SCALAR(facts::CMD_Info, Kicker_voltage)},
         {"justKicked", SCALAR(facts::CMD_Info, justKicked)}}}},
      {"CMD_HWERRORS", {sizeof(facts::CMD_HWerrors), hwerrors}},
      {"CMD_IMU",
       {sizeof(facts::CMD_Imu),
        {{"compass", SCALAR(facts::CMD_Imu, compass)},
         {"yaw", SCALAR(facts::CMD_Imu, yaw)},
         {"rawYaw", SCALAR(facts::CMD_Imu, rawYaw)}}}},
      {"CMD_SYNCIMU", {sizeof(int), {}}},
      {"CMD_GRABBER_INFO",
       {sizeof(facts::CMD_Grabber_Info),
        {{"leftArm", SCALAR(facts::CMD_Grabber_Info, leftArm)},
         {"rightArm", SCALAR(facts::CMD_Grabber_Info, rightArm)},
         {"leftHandicapped", SCALAR(facts::CMD_Grabber_Info, leftHandicapped)},
         {"rightHandicapped", SCALAR(facts::CMD_Grabber_Info, rightHandicapped)}}}},
      {"CMD_GRABBER_CONFIG",
       {sizeof(facts::CMD_Grabber_Config), {{"configId", SCALAR(facts::CMD_Grabber_Config, configId)}}}},
      {"COACH_INFO",
       {sizeof(facts::CoachInfo),
        {{"playerInfo.role", OF_EACH(facts::CoachInfo, playerInfo, role, 1)},
         {"playerInfo.teamColor", OF_EACH(facts::CoachInfo, playerInfo, teamColor, 1)},
         {"playerInfo.goalColor", OF_EACH(facts::CoachInfo, playerInfo, goalColor, 1)},
         {"playerInfo.roleAuto", OF_EACH(facts::CoachInfo, playerInfo, roleAuto, 1)},
         {"playerInfo.running", OF_EACH(facts::CoachInfo, playerInfo, running, 1)},
         {"playerInfo.coaching", OF_EACH(facts::CoachInfo, playerInfo, coaching, 1)},
         {"playerInfo.orientation", OF_EACH(facts::CoachInfo, playerInfo, orientation, 1)},
         {"playerInfo.pos", OF_EACH(facts::CoachInfo, playerInfo, pos, 2)},
         {"playerInfo.number", OF_EACH(facts::CoachInfo, playerInfo, number, 1)},
         {"changePositionSN", ARRAY(facts::CoachInfo, changePositionSN, )},
         {"gameState", SCALAR(facts::CoachInfo, gameState)},
         {"ourGoals", SCALAR(facts::CoachInfo, ourGoals)},
         {"theirGoals", SCALAR(facts::CoachInfo, theirGoals)},
         {"time", SCALAR(facts::CoachInfo, time)},
         {"manualFormation", SCALAR(facts::CoachInfo, manualFormation)},
         {"half", SCALAR(facts::CoachInfo, half)},
         {"taxiRobotSN", ARRAY(facts::CoachInfo, taxiRobotSN, )},
         {"taxiPos", Expect{offsetof(facts::CoachInfo, taxiPos), sizeof(float), 1, sizeof(facts::Vec), 2}},
         {"taxiOri", SCALAR(facts::CoachInfo, taxiOri)}}}},
      {"FORMATION_INFO",
       {sizeof(facts::FormationInfo),
        {{"formationIdFreePlay", SCALAR(facts::FormationInfo, formationIdFreePlay)},
         {"formationIdSP", SCALAR(facts::FormationInfo, formationIdSP)},
         {"position", VEC_ARRAY(facts::FormationInfo, position)},
         {"posId", ARRAY(facts::FormationInfo, posId, )},
         {"cover", ARRAY(facts::FormationInfo, cover, )}}}},
      {"ROBOT_WS", {sizeof(facts::Robot), {}}},
      {"LAPTOP_INFO",
       {sizeof(facts::LaptopInfo),
        {{"status", SCALAR(facts::LaptopInfo, status)}, {"charge", SCALAR(facts::LaptopInfo, charge)}}}},
      {"FRONT_VISION_INFO",
       {sizeof(facts::FrontVisionInfo),
        {{"ball.position", OF_EACH(facts::FrontVisionInfo, ball, position, 2)},
         {"ball.height", OF_EACH(facts::FrontVisionInfo, ball, height, 1)},
         {"ball.cyclesNotVisible", OF_EACH(facts::FrontVisionInfo, ball, cyclesNotVisible, 1)}}}},
      {"KICKCALIB_APP",
       {sizeof(facts::KickCalibAppData),
        {{"robotNumber", SCALAR(facts::KickCalibAppData, robotNumber)},
         {"power", SCALAR(facts::KickCalibAppData, power)},
         {"distance", SCALAR(facts::KickCalibAppData, distance)},
         {"active", SCALAR(facts::KickCalibAppData, active)},
         {"kick", SCALAR(facts::KickCalibAppData, kick)}}}},
      {"KICKCALIB_ROB",
       {sizeof(facts::KickCalibRobData),
        {{"stopped", SCALAR(facts::KickCalibRobData, stopped)},
         {"kicked", SCALAR(facts::KickCalibRobData, kicked)},
         {"distance", SCALAR(facts::KickCalibRobData, distance)},
         {"power", SCALAR(facts::KickCalibRobData, power)}}}},
      {"GRIDVIEW", {sizeof(facts::GridView), {}}},
      {"COACHLOGROBOTSINFO", {sizeof(facts::CoachLogRobotsInfo), {}}},
      {"COACHLOGMODEFLAG", {sizeof(facts::CoachLogModeFlag), {}}},
  };
}

std::map<std::string, ItemExpect> canhil_structs() {
  const Fields vel{{"vx", SCALAR(CMD_Vel, vx)},
                   {"vy", SCALAR(CMD_Vel, vy)},
                   {"va", SCALAR(CMD_Vel, va)},
                   {"smallAdjustment", SCALAR(CMD_Vel, smallAdjustment)}};
  Fields hwerrors = cambada_structs().at("CMD_HWERRORS").fields;
  static_assert(sizeof(CMD_HWerrors) == sizeof(facts::CMD_HWerrors));
  return {
      {"VISION_INFO",
       {sizeof(VisionInfo),
        {{"obstacles.nPoints", SCALAR(VisionInfo, obstacles.nPoints)},
         {"obstacles.point", VEC_ARRAY(VisionInfo, obstacles.point)},
         {"linePoints.nPoints", SCALAR(VisionInfo, linePoints.nPoints)},
         {"linePoints.point", VEC_ARRAY(VisionInfo, linePoints.point)},
         {"ball", VEC_ARRAY(VisionInfo, ball)},
         {"nBalls", SCALAR(VisionInfo, nBalls)}}}},
      {"CMD_VEL", {sizeof(CMD_Vel), vel}},
      {"CMD_POS",
       {sizeof(CMD_Pos),
        {{"px", SCALAR(CMD_Pos, px)},
         {"py", SCALAR(CMD_Pos, py)},
         {"pa", SCALAR(CMD_Pos, pa)},
         {"dx", SCALAR(CMD_Pos, dx)},
         {"dy", SCALAR(CMD_Pos, dy)},
         {"da", SCALAR(CMD_Pos, da)}}}},
      {"CMD_KICKER",
       {sizeof(CMD_Kicker),
        {{"power", SCALAR(CMD_Kicker, power)},
         {"engLvlHigh", SCALAR(CMD_Kicker, engLvlHigh)},
         {"engLvlLow", SCALAR(CMD_Kicker, engLvlLow)}}}},
      {"CMD_GRABBER", {sizeof(CMD_Grabber), {{"mode", SCALAR(CMD_Grabber, mode)}}}},
      {"CMD_INFO",
       {sizeof(CMD_Info),
        {{"Voltage_logic", SCALAR(CMD_Info, Voltage_logic)},
         {"Voltage_power12", SCALAR(CMD_Info, Voltage_power12)},
         {"Voltage_power24", SCALAR(CMD_Info, Voltage_power24)},
         {"Kicker_voltage", SCALAR(CMD_Info, Kicker_voltage)},
         {"justKicked", SCALAR(CMD_Info, justKicked)}}}},
      {"CMD_IMU",
       {sizeof(CMD_Imu),
        {{"compass", SCALAR(CMD_Imu, compass)}, {"yaw", SCALAR(CMD_Imu, yaw)}, {"rawYaw", SCALAR(CMD_Imu, rawYaw)}}}},
      {"CMD_HWERRORS", {sizeof(CMD_HWerrors), hwerrors}},
      {"CMD_GRABBER_INFO",
       {sizeof(CMD_Grabber_Info),
        {{"ballEngaged", SCALAR(CMD_Grabber_Info, ballEngaged)},
         {"grabberMode", SCALAR(CMD_Grabber_Info, grabberMode)}}}},
      {"CMD_SETPOSE",
       {sizeof(CMD_SetPose),
        {{"px", SCALAR(CMD_SetPose, px)},
         {"py", SCALAR(CMD_SetPose, py)},
         {"pa", SCALAR(CMD_SetPose, pa)},
         {"command", SCALAR(CMD_SetPose, command)},
         {"pending", SCALAR(CMD_SetPose, pending)}}}},
      {"ROBOT_WS",
       {sizeof(RobotWS),
        {{"x", SCALAR(RobotWS, x)},
         {"y", SCALAR(RobotWS, y)},
         {"orientation", SCALAR(RobotWS, orientation)},
         {"running", SCALAR(RobotWS, running)},
         {"frame", SCALAR(RobotWS, frame)}}}},
      {"COACH_INFO",
       {sizeof(CoachInfo), {{"gameState", SCALAR(CoachInfo, gameState)}, {"formation", SCALAR(CoachInfo, formation)}}}},
  };
}

// Every item and field of the layout is in the structs and the other way round.
void expect_byte_exact(const Layout& layout, const std::map<std::string, ItemExpect>& structs) {
  for (const std::string& name : layout.items()) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(structs.count(name)) << "no C struct declared for " << name;
    const ItemLayout& item = *layout.item(name);
    const ItemExpect& want = structs.at(name);
    EXPECT_EQ(item.size_bytes(), want.size);
    for (const FieldLayout& f : item.fields()) {
      SCOPED_TRACE(f.name);
      ASSERT_TRUE(want.fields.count(f.name)) << "no such member";
      const Expect got{f.offset_bytes, size_of(f.type), f.count, f.stride_bytes, f.components};
      const Expect& w = want.fields.at(f.name);
      EXPECT_EQ(got.offset, w.offset);
      EXPECT_EQ(got.scalar, w.scalar);
      EXPECT_EQ(got.count, w.count);
      EXPECT_EQ(got.components, w.components);
      if (w.count > 1) {
        EXPECT_EQ(got.stride, w.stride);
      }
    }
    EXPECT_EQ(item.fields().size(), want.fields.size()) << "members the layout leaves out";
  }
  EXPECT_EQ(layout.items().size(), structs.size()) << "declared items the layout leaves out";
}

TEST(ShippedLayouts, CambadaIsByteExactToThePublishedStructs) {
  const Layout layout = Layout::shipped("cambada");
  EXPECT_EQ(layout.name(), "cambada");
  expect_byte_exact(layout, cambada_structs());
}

TEST(ShippedLayouts, CanhilIsByteExactToItsOwnHeader) {
  const Layout layout = Layout::shipped("canhil");
  EXPECT_EQ(layout.name(), "canhil");
  expect_byte_exact(layout, canhil_structs());
}

TEST(ShippedLayouts, UnknownNameListsTheChoices) {
  try {
    Layout::shipped("nope");
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("nope"), std::string::npos) << what;
    EXPECT_NE(what.find("cambada"), std::string::npos) << what;
    EXPECT_NE(what.find("canhil"), std::string::npos) << what;
  }
  EXPECT_TRUE(std::filesystem::exists(Layout::shipped_path("cambada")));
  EXPECT_TRUE(std::filesystem::exists(Layout::shipped_path("canhil")));
}

TEST(ShippedLayouts, LayoutDirOverridesWhereTheyAreFound) {
  ASSERT_EQ(setenv("CANHIL_LAYOUT_DIR", "/nowhere/layouts", 1), 0);
  const std::filesystem::path path = Layout::shipped_path("cambada");
  EXPECT_THROW(Layout::shipped("cambada"), LayoutError) << "no such file there";
  unsetenv("CANHIL_LAYOUT_DIR");
  EXPECT_EQ(path, "/nowhere/layouts/cambada.toml");
}

TEST(ShippedLayouts, CarryEveryQuantityCanhilUses) {
  const Layout cambada = Layout::shipped("cambada");
  const Layout canhil = Layout::shipped("canhil");
  for (const QuantityInfo& q : contract()) {
    const bool cambada_lacks =
        q.item == "CMD_SETPOSE" || q.name == "raw" || (q.item == "CMD_GRABBER_INFO" && q.name == "grabber");
    const bool canhil_lacks = q.item == "LAST_CMD_VEL" || (q.item == "COACH_INFO" && q.name != "game_state");
    const ItemLayout* a = cambada.item(q.item);
    const ItemLayout* b = canhil.item(q.item);
    EXPECT_EQ(a != nullptr && a->has(q.name), !cambada_lacks) << "cambada " << q.item << "." << q.name;
    EXPECT_EQ(b != nullptr && b->has(q.name), !canhil_lacks) << "canhil " << q.item << "." << q.name;
  }
  EXPECT_EQ(cambada.item("VISION_INFO")->capacity("lines"), 500u);
  EXPECT_EQ(canhil.item("VISION_INFO")->capacity("lines"), 300u);
  EXPECT_EQ(cambada.item("COACH_INFO")->capacity("running"), 6u);
  EXPECT_EQ(cambada.item("CMD_POS")->deltas_frame(), DeltasFrame::kRobot);
  EXPECT_EQ(canhil.item("CMD_POS")->deltas_frame(), DeltasFrame::kOdometry);
}

// A test value per quantity, in SI.
double sample(const QuantityInfo& q) {
  static const std::map<std::string_view, double> kValues{
      {"vx", 1.25},          {"vy", -0.75},       {"va", 2.5},        {"kick", 0x80 | 50}, {"eng_level_high", 70},
      {"eng_level_low", 35}, {"grabber", 0.57},   {"x", 3.25},        {"y", -1.5},         {"dx", 0.0123},
      {"dy", -0.004},        {"dheading", 0.05},  {"v_logic", 12.34}, {"v_power12", 24.1}, {"v_power24", 25.2},
      {"v_kicker", 380.5},   {"raw", -321},       {"bad_frames", 17}, {"alive", 0x3F},     {"node_state", 2},
      {"wrong_length", 3},   {"out_of_range", 4}, {"unknown_id", 5},  {"missed_tms", 6},   {"send_failed", 7},
      {"command", 1},        {"relocations", 12}};
  if (q.kind == QuantityKind::kBool) return 1;
  if (q.kind == QuantityKind::kCount) return 3;
  if (q.name == "heading") return q.clockwise ? 123.4 : 2.0;  // CMD_IMU in deg; CMD_POS, CMD_SETPOSE in rad
  return kValues.at(q.name);
}

// set then get gives the value back within the stored type's resolution (and
// modulo a turn where the field wraps), for every quantity of both layouts.
TEST(ShippedLayouts, EveryQuantityRoundTrips) {
  for (const char* name : {"cambada", "canhil"}) {
    const Layout layout = Layout::shipped(name);
    for (const std::string& item_name : layout.items()) {
      const ItemLayout& item = *layout.item(item_name);
      ItemBuffer buf(item);
      for (std::string_view qn : item.quantities()) {
        SCOPED_TRACE(std::string(name) + " " + item_name + "." + std::string(qn));
        const QuantityInfo& info = *find_quantity(item_name, qn);
        const Quantity q = buf.quantity(qn);
        const std::size_t index = info.per_agent ? 2 : 0;
        if (info.kind == QuantityKind::kPoints) {
          const std::array<std::array<double, 2>, 2> pts{{{1.5, -2.25}, {0.125, 3.0}}};
          buf.set_points(q, pts);
          EXPECT_EQ(buf.get_point(q, 1)[0], 0.125);
          EXPECT_EQ(buf.get_point(q, 1)[1], 3.0);
          continue;
        }
        if (info.kind == QuantityKind::kEnum) {
          const std::string_view value =
              info.names[std::min<std::size_t>(3, info.names.size() - 1)];  // ready, striker, cyan, negative_x
          buf.set(q, value, index);
          EXPECT_EQ(buf.get_enum(q, index), value);
          continue;
        }
        const double v = sample(info);
        buf.set(q, v, index);
        const FieldLayout* f = nullptr;
        for (const FieldLayout& g : item.fields()) {
          if (g.quantity == qn && f == nullptr) f = &g;
        }
        const bool integer = f->type != ScalarType::kF32 && f->type != ScalarType::kF64;
        const double resolution = integer ? 0.5 / std::fabs(f->stored_per_si) : std::fabs(v) * 1e-6;
        double diff = buf.get(q, index) - v;
        if (f->turn > 0) {
          const double turn_si = f->turn / std::fabs(f->stored_per_si);
          diff = std::remainder(diff, turn_si);
        }
        EXPECT_LE(std::fabs(diff), resolution + 1e-9) << "got " << buf.get(q, index);
      }
    }
  }
}

}  // namespace
}  // namespace canhil::rtdb
