// Values written through the shipped layouts, read back through the C
// structs (and the other way for commands): CAMBADA's units and conventions
// where its agent expects them, and canhil's layout reproducing exactly the
// bytes canhil's handler and vision write today.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "canhil/rtdb/cambada_types.h"
#include "canhil/rtdb/layout.hpp"
#include "rtdb/cambada_facts.hpp"

namespace canhil::rtdb {
namespace {

template <class T>
T as(const ItemBuffer& buf) {
  EXPECT_EQ(buf.bytes().size(), sizeof(T));
  T out;
  std::memcpy(&out, buf.data(), sizeof(T));
  return out;
}

template <class T>
void from(ItemBuffer& buf, const T& value) {
  ASSERT_EQ(buf.bytes().size(), sizeof(T));
  std::memcpy(buf.data(), &value, sizeof(T));
}

class CambadaLayout : public ::testing::Test {
 protected:
  ItemBuffer buffer(const char* item) { return ItemBuffer(*layout_.item(item)); }
  Layout layout_ = Layout::shipped("cambada");
};

TEST_F(CambadaLayout, VisionInfoLinesInMillimetresTheRestInMetres) {
  ItemBuffer buf = buffer("VISION_INFO");
  const std::array<std::array<double, 2>, 1> obstacles{{{0.5, 1.5}}};
  const std::array<std::array<double, 2>, 2> lines{{{1.0, 2.0}, {-0.5, 0.25}}};
  const std::array<std::array<double, 2>, 1> balls{{{0.3, 2.0}}};
  buf.set_points(buf.quantity("obstacles"), obstacles);
  buf.set_points(buf.quantity("lines"), lines);
  buf.set_points(buf.quantity("balls"), balls);
  const auto v = std::make_unique<facts::VisionInfo>(as<facts::VisionInfo>(buf));
  EXPECT_EQ(v->obstacles.nPoints, 1);
  EXPECT_EQ(v->obstacles.point[0].x, 0.5f);
  EXPECT_EQ(v->obstacles.point[0].y, 1.5f);
  EXPECT_EQ(v->lines.nPoints, 2);
  EXPECT_EQ(v->lines.point[0].x, 1000.0f);
  EXPECT_EQ(v->lines.point[0].y, 2000.0f);
  EXPECT_EQ(v->lines.point[1].x, -500.0f);
  EXPECT_EQ(v->lines.point[1].y, 250.0f);
  EXPECT_EQ(v->nBalls, 1);
  EXPECT_EQ(v->ball[0].position.x, 0.3f);
  EXPECT_EQ(v->ball[0].position.y, 2.0f);
}

TEST_F(CambadaLayout, PointsInMetresAreRoundedToFloatsClampedToTheirRangeAndNonFiniteOnesKept) {
  ItemBuffer buf = buffer("VISION_INFO");
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::nan("");
  constexpr float kMax = std::numeric_limits<float>::max();
  // A list with values beyond float's range, and one without (a NaN is in neither range).
  const std::array<std::array<double, 2>, 4> wide{{{0.1, -0.2}, {1e300, -1e39}, {inf, -inf}, {nan, 1e-50}}};
  const std::array<std::array<double, 2>, 3> narrow{{{0.1, -0.2}, {nan, 3.5}, {-3.4e38, 3.4e38}}};
  buf.set_points(buf.quantity("obstacles"), wide);
  auto v = std::make_unique<facts::VisionInfo>(as<facts::VisionInfo>(buf));
  EXPECT_EQ(v->obstacles.nPoints, 4);
  EXPECT_EQ(v->obstacles.point[0].x, 0.1f);
  EXPECT_EQ(v->obstacles.point[0].y, -0.2f);
  EXPECT_EQ(v->obstacles.point[1].x, kMax);
  EXPECT_EQ(v->obstacles.point[1].y, -kMax);
  EXPECT_EQ(v->obstacles.point[2].x, std::numeric_limits<float>::infinity());
  EXPECT_EQ(v->obstacles.point[2].y, -std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(v->obstacles.point[3].x));
  EXPECT_EQ(v->obstacles.point[3].y, 0.0f);
  buf.set_points(buf.quantity("obstacles"), narrow);
  v = std::make_unique<facts::VisionInfo>(as<facts::VisionInfo>(buf));
  EXPECT_EQ(v->obstacles.nPoints, 3);
  EXPECT_EQ(v->obstacles.point[0].x, 0.1f);
  EXPECT_EQ(v->obstacles.point[0].y, -0.2f);
  EXPECT_TRUE(std::isnan(v->obstacles.point[1].x));
  EXPECT_EQ(v->obstacles.point[1].y, 3.5f);
  EXPECT_EQ(v->obstacles.point[2].x, -3.4e38f);
  EXPECT_EQ(v->obstacles.point[2].y, 3.4e38f);
}

TEST_F(CambadaLayout, CommandsReadBackInSi) {
  ItemBuffer vel = buffer("CMD_VEL");
  from(vel, facts::CMD_Vel{1.0f, -2.0f, 0.5f, true});
  EXPECT_EQ(vel.get(vel.quantity("vx")), 1.0);
  EXPECT_EQ(vel.get(vel.quantity("vy")), -2.0);
  EXPECT_EQ(vel.get(vel.quantity("va")), 0.5);
  EXPECT_EQ(vel.get(vel.quantity("small_adjustment")), 1.0);
  ItemBuffer kicker = buffer("CMD_KICKER");
  from(kicker, facts::CMD_Kicker{0x80 | 30, 70, 35});
  EXPECT_EQ(kicker.get(kicker.quantity("kick")), 0x80 | 30);
  EXPECT_EQ(kicker.get(kicker.quantity("eng_level_high")), 70);
  EXPECT_EQ(kicker.get(kicker.quantity("eng_level_low")), 35);
  kicker.set(kicker.quantity("kick"), 0);  // the handler clears the kick it sent
  EXPECT_EQ(as<facts::CMD_Kicker>(kicker).power, 0);
  EXPECT_EQ(as<facts::CMD_Kicker>(kicker).engLvlHigh, 70);
  ItemBuffer grabber = buffer("CMD_GRABBER");
  from(grabber, facts::CMD_Grabber{1});
  EXPECT_EQ(grabber.get(grabber.quantity("grabber")), 1.0);
  grabber.set(grabber.quantity("grabber"), 1.0);
  EXPECT_EQ(as<facts::CMD_Grabber>(grabber).mode, 1);
}

TEST_F(CambadaLayout, HandlerItems) {
  ItemBuffer last = buffer("LAST_CMD_VEL");
  last.set(last.quantity("vx"), 0.25);
  last.set(last.quantity("va"), -1.5);
  EXPECT_EQ(as<facts::CMD_Vel>(last).vx, 0.25f);
  EXPECT_EQ(as<facts::CMD_Vel>(last).va, -1.5f);

  ItemBuffer pos = buffer("CMD_POS");
  pos.set(pos.quantity("x"), 1.5);
  pos.set(pos.quantity("heading"), -0.5);
  pos.set(pos.quantity("dx"), 0.012);
  pos.set(pos.quantity("dy"), -0.25);
  pos.set(pos.quantity("dheading"), 0.01);
  const auto p = as<facts::CMD_Pos>(pos);
  EXPECT_EQ(p.px, 1.5f);
  EXPECT_FLOAT_EQ(p.pa, static_cast<float>(2 * std::numbers::pi - 0.5)) << "[0, 2 pi)";
  EXPECT_FLOAT_EQ(p.dx, 12.0f) << "mm";
  EXPECT_FLOAT_EQ(p.dy, -250.0f);
  EXPECT_FLOAT_EQ(p.da, 0.01f);

  ItemBuffer info = buffer("CMD_INFO");
  info.set(info.quantity("v_logic"), 7.4);
  info.set(info.quantity("v_power12"), 15.04);
  info.set(info.quantity("v_power24"), 14.96);
  info.set(info.quantity("v_kicker"), 40.0);
  info.set(info.quantity("just_kicked"), 1);
  const auto i = as<facts::CMD_Info>(info);
  EXPECT_EQ(i.Voltage_logic, 74);
  EXPECT_EQ(i.Voltage_power12, 150);
  EXPECT_EQ(i.Voltage_power24, 150);
  EXPECT_EQ(i.Kicker_voltage, 400);
  EXPECT_TRUE(i.justKicked);

  ItemBuffer arms = buffer("CMD_GRABBER_INFO");
  arms.set(arms.quantity("ball_engaged"), 1);
  EXPECT_EQ(as<facts::CMD_Grabber_Info>(arms).leftArm, 100u);
  EXPECT_EQ(as<facts::CMD_Grabber_Info>(arms).rightArm, 100u);
  EXPECT_FALSE(as<facts::CMD_Grabber_Info>(arms).leftHandicapped);
  EXPECT_EQ(arms.get(arms.quantity("ball_engaged")), 1.0);
  arms.set(arms.quantity("ball_engaged"), 0);
  EXPECT_EQ(as<facts::CMD_Grabber_Info>(arms).leftArm, 0u);
  EXPECT_EQ(as<facts::CMD_Grabber_Info>(arms).rightArm, 0u);
  EXPECT_FALSE(arms.quantity("grabber")) << "CAMBADA has no grabber state";

  ItemBuffer errors = buffer("CMD_HWERRORS");
  errors.set(errors.quantity("bad_frames"), 70000);
  errors.set(errors.quantity("alive"), 0x3F);
  errors.set(errors.quantity("send_failed"), 9);
  const auto e = as<facts::CMD_HWerrors>(errors);
  EXPECT_EQ(e.error_count[0][0], 65535) << "saturated";
  EXPECT_EQ(e.error_count[0][1], 0x3F);
  EXPECT_EQ(e.error_count[1][4], 9);
}

// yaw = heading counter-clockwise + theNorth (-80), whole degrees in [-180, 180).
TEST_F(CambadaLayout, CompassIsCounterClockwisePlusTheNorth) {
  ItemBuffer imu = buffer("CMD_IMU");
  for (const double cw : {0.0, 10.0, 90.0, 100.0, 181.2, 270.0, 359.9}) {
    imu.set(imu.quantity("heading"), cw);
    long want = std::lround(-cw - 80);
    want = ((want + 180) % 360 + 360) % 360 - 180;
    const auto got = as<facts::CMD_Imu>(imu);
    EXPECT_EQ(got.yaw, want) << cw;
    EXPECT_EQ(got.compass, want) << cw;
    EXPECT_EQ(got.rawYaw, want) << cw;
  }
  imu.set(imu.quantity("heading"), 0);
  EXPECT_EQ(as<facts::CMD_Imu>(imu).yaw, -80) << "facing the opponent goal: yaw - theNorth = 0";
}

TEST_F(CambadaLayout, CoachInfoPerRobot) {
  ItemBuffer coach = buffer("COACH_INFO");
  coach.set(coach.quantity("running"), 1, 2);
  coach.set(coach.quantity("role_auto"), 1, 2);
  coach.set(coach.quantity("role"), "striker", 2);
  coach.set(coach.quantity("team_color"), "yellow", 2);
  coach.set(coach.quantity("game_state"), "start");
  const auto c = as<facts::CoachInfo>(coach);
  EXPECT_TRUE(c.playerInfo[1].running);
  EXPECT_FALSE(c.playerInfo[0].running);
  EXPECT_FALSE(c.playerInfo[2].running);
  EXPECT_TRUE(c.playerInfo[1].roleAuto);
  EXPECT_EQ(c.playerInfo[1].role, 3);
  EXPECT_EQ(c.playerInfo[1].teamColor, 1);
  EXPECT_EQ(c.gameState, 3);
  for (const facts::PlayerInfo& p : c.playerInfo) EXPECT_EQ(p.goalColor, 0) << "nothing set yet: 0, Blue";
  // The team's goal as CAMBADA is told it: Yellow attacks with the compass as
  // it reads (+x), Blue turns it by 180 degrees (-x).
  coach.set(coach.quantity("attacks"), "positive_x", 1);
  coach.set(coach.quantity("attacks"), "negative_x", 2);
  EXPECT_EQ(as<facts::CoachInfo>(coach).playerInfo[0].goalColor, 1) << "Yellow";
  EXPECT_EQ(as<facts::CoachInfo>(coach).playerInfo[1].goalColor, 0) << "Blue";
  EXPECT_THROW(coach.set(coach.quantity("attacks"), "+x", 1), LayoutError) << "the contract's names only";
  coach.set(coach.quantity("running"), 1, 7);  // no seventh robot: nothing written
  coach.set(coach.quantity("running"), 1, 0);
  EXPECT_EQ(as<facts::CoachInfo>(coach).playerInfo[5].running, false);
  EXPECT_EQ(coach.get(coach.quantity("running"), 7), 0.0);
  EXPECT_THROW(coach.set(coach.quantity("game_state"), "kickoff"), LayoutError);
  EXPECT_EQ(as<facts::CoachInfo>(coach).gameState, 3) << "a refused name writes nothing";
}

// CAMBADA's agent relocalises from scratch when its changePositionSN changes
// (its Integrator: "Reloc by baseReloc"): canhil's count of the robot's moves.
TEST_F(CambadaLayout, RelocationsAreEachRobotsChangePositionSerial) {
  ItemBuffer coach = buffer("COACH_INFO");
  const Quantity relocations = coach.quantity("relocations");
  ASSERT_TRUE(relocations) << "COACH_INFO.changePositionSN carries relocations";
  coach.set(relocations, 3, 2);
  coach.set(relocations, 1, 6);
  const auto c = as<facts::CoachInfo>(coach);
  EXPECT_EQ(c.changePositionSN[0], 0);
  EXPECT_EQ(c.changePositionSN[1], 3) << "agent 2's";
  EXPECT_EQ(c.changePositionSN[5], 1) << "agent 6's";
  for (const facts::PlayerInfo& p : c.playerInfo) EXPECT_EQ(p.number, 0) << "nothing else written";
  EXPECT_EQ(coach.get(relocations, 2), 3.0);
}

// canhil's layout writes exactly what canhil-hwcomm and the vision write today
// (laptop/src/hwcomm.cpp, vision_emu/src/runner.cpp), computed here their way.
class CanhilLayout : public CambadaLayout {
 protected:
  CanhilLayout() { layout_ = Layout::shipped("canhil"); }
};

TEST_F(CanhilLayout, VisionInfoAsTheVisionWritesIt) {
  std::vector<std::array<double, 2>> obstacles, lines;
  for (int i = 0; i < 350; ++i) obstacles.push_back({0.01 * i, -0.02 * i});  // more than the 300 that fit
  for (int i = 0; i < 10; ++i) lines.push_back({1.0 / (i + 1), 2.5 - i});
  const std::array<std::array<double, 2>, 1> balls{{{0.3, 2.1}}};
  auto today = std::make_unique<VisionInfo>();
  today->obstacles.nPoints = MAX_POINTS;
  for (int i = 0; i < MAX_POINTS; ++i) {
    today->obstacles.point[i] = {static_cast<float>(obstacles[static_cast<std::size_t>(i)][0]),
                                 static_cast<float>(obstacles[static_cast<std::size_t>(i)][1])};
  }
  today->linePoints.nPoints = 10;
  for (int i = 0; i < 10; ++i) {
    today->linePoints.point[i] = {static_cast<float>(lines[static_cast<std::size_t>(i)][0]),
                                  static_cast<float>(lines[static_cast<std::size_t>(i)][1])};
  }
  today->nBalls = 1;
  today->ball[0] = {0.3f, 2.1f};
  ItemBuffer buf = buffer("VISION_INFO");
  buf.set_points(buf.quantity("obstacles"), obstacles);
  buf.set_points(buf.quantity("lines"), lines);
  buf.set_points(buf.quantity("balls"), balls);
  EXPECT_EQ(std::memcmp(buf.data(), today.get(), sizeof(VisionInfo)), 0);
}

TEST(ItemBufferReplace, ReplacingPointListsFrameAfterFrameGivesTheBytesOfAFreshWrite) {
  // Both shipped layouts (CAMBADA's stores lines in millimetres), lists that
  // grow, shrink, empty and overflow in random order.
  for (const char* name : {"canhil", "cambada"}) {
    const Layout layout = Layout::shipped(name);
    const ItemLayout& item = *layout.item("VISION_INFO");
    ItemBuffer kept(item);
    // A copy of kept's bytes that is given only the ranges replace_points
    // says it changed (what Database::put_ranges copies into the slot).
    std::vector<std::byte> slot(kept.bytes().begin(), kept.bytes().end());
    std::vector<ByteRange> changed;
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> length(0, 320);
    std::uniform_real_distribution<double> metres(-9, 9);
    for (int frame = 0; frame < 200; ++frame) {
      ItemBuffer fresh(item);
      changed.clear();
      for (const char* list : {"obstacles", "lines", "balls"}) {
        std::vector<std::array<double, 2>> points(static_cast<std::size_t>(frame % 7 == 3 ? 0 : length(rng)));
        for (auto& p : points) p = {metres(rng), metres(rng)};
        kept.replace_points(kept.quantity(list), points, &changed);
        fresh.set_points(fresh.quantity(list), points);
      }
      ASSERT_EQ(std::memcmp(kept.data(), fresh.data(), kept.bytes().size()), 0) << name << " frame " << frame;
      std::size_t copied = 0;
      for (const ByteRange& r : changed) {
        ASSERT_LE(r.offset + r.size, slot.size()) << name;
        std::memcpy(slot.data() + r.offset, kept.bytes().data() + r.offset, r.size);
        copied += r.size;
      }
      ASSERT_EQ(std::memcmp(slot.data(), kept.data(), slot.size()), 0)
          << name << " frame " << frame << ": a change outside the ranges given";
      EXPECT_GT(copied, 0u);
    }
    // Short lists after empty ones: the ranges are those few points and the counts, not the item.
    for (const std::size_t n : {std::size_t{0}, std::size_t{10}}) {
      changed.clear();
      const std::vector<std::array<double, 2>> points(n, {1.0, 2.0});
      for (const char* list : {"obstacles", "lines", "balls"})
        kept.replace_points(kept.quantity(list), points, &changed);
      std::size_t copied = 0;
      for (const ByteRange& r : changed) copied += r.size;
      if (n == 10) {
        EXPECT_LE(copied, 3u * 10 * 8 + 3 * 4) << name;
      }
    }
  }
}

TEST_F(CanhilLayout, HandlerItemsAsTheHandlerWritesThem) {
  const auto sat16 = [](double v) { return static_cast<unsigned short>(std::clamp(std::lround(v), 0L, 65535L)); };
  ItemBuffer info = buffer("CMD_INFO");
  for (const double v : {0.0, 7.404, 12.345, 12.355, 24.999, -1.0, 700.0}) {
    info.set(info.quantity("v_logic"), v);
    info.set(info.quantity("v_kicker"), v / 2);
    info.set(info.quantity("just_kicked"), 1);
    CMD_Info today{};
    today.Voltage_logic = sat16(v * 100);
    today.Kicker_voltage = sat16(v / 2 * 100);
    today.justKicked = true;
    EXPECT_EQ(std::memcmp(info.data(), &today, sizeof today), 0) << v;
  }
  ItemBuffer imu = buffer("CMD_IMU");
  for (int i = 0; i <= 65535; i += 7) {  // every heading M8 can carry, 0.01 deg apart
    const double heading = i * 0.01;
    imu.set(imu.quantity("heading"), heading);
    imu.set(imu.quantity("raw"), -i / 3);
    const CMD_Imu today{static_cast<int>(std::lround(heading)) % 360, static_cast<int>(std::lround(heading * 100)),
                        -i / 3};
    ASSERT_EQ(std::memcmp(imu.data(), &today, sizeof today), 0) << heading;
  }
  ItemBuffer pos = buffer("CMD_POS");
  const CMD_Pos p{1.25f, -3.5f, 3.1f, 0.002f, -0.001f, -0.03f};
  for (const auto& [q, v] :
       {std::pair{"x", p.px}, {"y", p.py}, {"heading", p.pa}, {"dx", p.dx}, {"dy", p.dy}, {"dheading", p.da}}) {
    pos.set(pos.quantity(q), v);
  }
  EXPECT_EQ(std::memcmp(pos.data(), &p, sizeof p), 0);
  ItemBuffer grab = buffer("CMD_GRABBER_INFO");
  for (int g = 0; g <= 100; ++g) {
    grab.set(grab.quantity("ball_engaged"), g % 2);
    grab.set(grab.quantity("grabber"), g / 100.0);
    const CMD_Grabber_Info today{static_cast<unsigned char>(g % 2), static_cast<unsigned char>(g)};
    ASSERT_EQ(std::memcmp(grab.data(), &today, sizeof today), 0) << g;
  }
  ItemBuffer errors = buffer("CMD_HWERRORS");
  CMD_HWerrors today{};
  const std::array<std::pair<const char*, unsigned short*>, 8> cells{{{"bad_frames", &today.error_count[0][0]},
                                                                      {"alive", &today.error_count[0][1]},
                                                                      {"node_state", &today.error_count[0][2]},
                                                                      {"wrong_length", &today.error_count[1][0]},
                                                                      {"out_of_range", &today.error_count[1][1]},
                                                                      {"unknown_id", &today.error_count[1][2]},
                                                                      {"missed_tms", &today.error_count[1][3]},
                                                                      {"send_failed", &today.error_count[1][4]}}};
  unsigned short n = 11;
  for (const auto& [q, cell] : cells) {
    errors.set(errors.quantity(q), n);
    *cell = n;
    n = static_cast<unsigned short>(n * 3);
  }
  EXPECT_EQ(std::memcmp(errors.data(), &today, sizeof today), 0);
}

TEST_F(CanhilLayout, CommandsAsTheAgentWritesThem) {
  ItemBuffer grab = buffer("CMD_GRABBER");
  from(grab, CMD_Grabber{57});
  EXPECT_NEAR(grab.get(grab.quantity("grabber")), 0.57, 1e-12);
  ItemBuffer pose = buffer("CMD_SETPOSE");
  from(pose, CMD_SetPose{1.5f, -2.0f, 0.25f, 1, 1});
  EXPECT_EQ(pose.get(pose.quantity("x")), 1.5);
  EXPECT_EQ(pose.get(pose.quantity("y")), -2.0);
  EXPECT_EQ(pose.get(pose.quantity("heading")), 0.25);
  EXPECT_EQ(pose.get(pose.quantity("command")), 1.0);
  EXPECT_EQ(pose.get(pose.quantity("pending")), 1.0);
  pose.set(pose.quantity("pending"), 0);
  EXPECT_EQ(as<CMD_SetPose>(pose).pending, 0);
  ItemBuffer coach = buffer("COACH_INFO");
  coach.set(coach.quantity("game_state"), "start");
  coach.set(coach.quantity("running"), 1, 1);  // canhil's CoachInfo has no per-robot part: nothing happens
  EXPECT_EQ(as<CoachInfo>(coach).gameState, 3);
  EXPECT_EQ(as<CoachInfo>(coach).formation, 0);
}

}  // namespace
}  // namespace canhil::rtdb
