// ItemBuffer's conversions, both ways: every unit, every convention
// (direction, add, wrap, scale, true/false, enum values, rounding,
// saturation, per-agent arrays, list capacities, constants), and no
// allocation on the set/get path.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <numbers>
#include <string>
#include <vector>

#include "canhil/rtdb/layout.hpp"
#include "support/sanitizers.hpp"

// ThreadSanitizer's runtime defines the allocation operators itself (a
// static archive: a second definition does not link), so under TSan the
// allocation count and its test are left out; the plain and ASan flavours run it.
#define CANHIL_COUNT_ALLOCATIONS (!CANHIL_UNDER_TSAN)

#if CANHIL_COUNT_ALLOCATIONS
// Counts every allocation of this test program (the no-allocation test reads
// it). Every plain form is replaced, so that each allocation and its release
// meet in malloc and free (under AddressSanitizer too). Not inlined: g++ takes
// an inlined malloc/free pair for a mismatch.
namespace {
std::atomic<std::size_t> g_allocations{0};
void* allocate(std::size_t n) noexcept {
  ++g_allocations;
  return std::malloc(n == 0 ? 1 : n);
}
}  // namespace
[[gnu::noinline]] void* operator new(std::size_t n) {
  if (void* p = allocate(n)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t n) { return operator new(n); }
[[gnu::noinline]] void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return allocate(n); }
[[gnu::noinline]] void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return allocate(n); }
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
#endif

namespace canhil::rtdb {
namespace {

constexpr double kPi = std::numbers::pi;

// A layout of one field `f` in one item, its buffer and the quantity's handle.
struct One {
  One(const std::string& item, const std::string& quantity, const std::string& field, int size = 16)
      : layout(Layout::parse("[" + item + "]\nsize = " + std::to_string(size) + "\nf = " + field + "\n", "one.toml")),
        buf(*layout.item(item)),
        q(buf.quantity(quantity)) {}
  template <class T>
  T raw(std::size_t at = 0) const {
    T v;
    std::memcpy(&v, buf.bytes().data() + at, sizeof v);
    return v;
  }
  double stored_after(double si) {
    buf.set(q, si);
    return raw<double>();
  }
  Layout layout;
  ItemBuffer buf;
  Quantity q;
};

struct UnitRow {
  const char* item;
  const char* quantity;
  const char* unit;
  double si;
  double stored;
};

class EveryUnit : public ::testing::TestWithParam<UnitRow> {};

TEST_P(EveryUnit, ConvertsBothWays) {
  const UnitRow& r = GetParam();
  One one(r.item, r.quantity,
          std::string("{ type = \"f64\", offset = 0, from = \"") + r.quantity + "\", unit = \"" + r.unit + "\" }");
  EXPECT_NEAR(one.stored_after(r.si), r.stored, std::fabs(r.stored) * 1e-12);
  EXPECT_NEAR(one.buf.get(one.q), r.si, std::fabs(r.si) * 1e-12);
}

INSTANTIATE_TEST_SUITE_P(
    Units, EveryUnit,
    ::testing::Values(
        UnitRow{"CMD_POS", "x", "m", 1.2345, 1.2345}, UnitRow{"CMD_POS", "x", "cm", 1.2345, 123.45},
        UnitRow{"CMD_POS", "x", "mm", 1.2345, 1234.5}, UnitRow{"CMD_POS", "heading", "rad", 1.0, 1.0},
        UnitRow{"CMD_POS", "heading", "mrad", 1.0, 1000.0}, UnitRow{"CMD_POS", "heading", "deg", kPi / 2, 90.0},
        UnitRow{"CMD_POS", "heading", "cdeg", kPi / 2, 9000.0}, UnitRow{"CMD_VEL", "vx", "m/s", 1.5, 1.5},
        UnitRow{"CMD_VEL", "vx", "cm/s", 1.5, 150.0}, UnitRow{"CMD_VEL", "vx", "mm/s", 1.5, 1500.0},
        UnitRow{"CMD_VEL", "va", "rad/s", 0.5, 0.5}, UnitRow{"CMD_VEL", "va", "mrad/s", 0.5, 500.0},
        UnitRow{"CMD_VEL", "va", "deg/s", kPi, 180.0}, UnitRow{"CMD_INFO", "v_logic", "V", 12.5, 12.5},
        UnitRow{"CMD_INFO", "v_logic", "dV", 12.5, 125.0}, UnitRow{"CMD_INFO", "v_logic", "cV", 12.5, 1250.0},
        UnitRow{"CMD_INFO", "v_logic", "mV", 12.5, 12500.0},
        // CMD_IMU's heading is given in degrees (clockwise).
        UnitRow{"CMD_IMU", "heading", "deg", 90.0, 90.0}, UnitRow{"CMD_IMU", "heading", "cdeg", 90.0, 9000.0},
        UnitRow{"CMD_IMU", "heading", "rad", 90.0, kPi / 2}, UnitRow{"CMD_IMU", "heading", "mrad", 90.0, 500 * kPi},
        UnitRow{"CMD_KICKER", "kick", "1", 7.0, 7.0}));

TEST(Conversions, DeciAndCentiDegreesAreExact) {
  // deg -> cdeg is exactly 100: an integer field stores what lround(deg * 100) does.
  One one("CMD_IMU", "heading", R"({ type = "i32", offset = 0, from = "heading", unit = "cdeg" })");
  for (int i = 0; i < 36000; ++i) {
    one.buf.set(one.q, i * 0.01);
    ASSERT_EQ(one.raw<std::int32_t>(), std::lround(i * 0.01 * 100)) << i;
  }
}

TEST(Conversions, DirectionFlipsTheSign) {
  One va("CMD_VEL", "va", R"({ type = "f64", offset = 0, from = "va", unit = "rad/s", direction = "cw" })");
  EXPECT_EQ(va.stored_after(0.5), -0.5);
  EXPECT_EQ(va.buf.get(va.q), 0.5);
  One ccw("CMD_VEL", "va", R"({ type = "f64", offset = 0, from = "va", unit = "rad/s", direction = "ccw" })");
  EXPECT_EQ(ccw.stored_after(0.5), 0.5) << "va is counter-clockwise already";
  One imu("CMD_IMU", "heading", R"({ type = "f64", offset = 0, from = "heading", unit = "deg", direction = "ccw" })");
  EXPECT_EQ(imu.stored_after(30), -30.0) << "the compass is clockwise";
  EXPECT_EQ(imu.buf.get(imu.q), 30.0);
}

TEST(Conversions, AddAndScale) {
  One add("CMD_POS", "x", R"({ type = "f64", offset = 0, from = "x", unit = "mm", add = 100 })");
  EXPECT_EQ(add.stored_after(1.0), 1100.0) << "added in the stored unit, after conversion";
  EXPECT_EQ(add.buf.get(add.q), 1.0);
  One scale("CMD_GRABBER", "grabber", R"({ type = "u8", offset = 0, from = "grabber", scale = 100 })");
  scale.buf.set(scale.q, 0.5);
  EXPECT_EQ(scale.raw<std::uint8_t>(), 50);
  EXPECT_EQ(scale.buf.get(scale.q), 0.5);
  One both("CMD_GRABBER", "grabber", R"({ type = "f64", offset = 0, from = "grabber", scale = 2, add = -1 })");
  EXPECT_EQ(both.stored_after(0.25), -0.5);
  EXPECT_EQ(both.buf.get(both.q), 0.25);
}

struct WrapRow {
  const char* field;
  double si;
  double stored;
};
class Wraps : public ::testing::TestWithParam<WrapRow> {};

TEST_P(Wraps, IntoTheRangeOfTheStoredUnit) {
  One one("CMD_POS", "heading", GetParam().field);
  one.buf.set(one.q, GetParam().si);
  const double got =
      one.layout.item("CMD_POS")->fields()[0].type == ScalarType::kI32 ? one.raw<std::int32_t>() : one.raw<double>();
  EXPECT_NEAR(got, GetParam().stored, 1e-9) << GetParam().field << " " << GetParam().si;
}

INSTANTIATE_TEST_SUITE_P(
    EachRange, Wraps,
    ::testing::Values(
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "0..360" })", -kPi / 2, 270},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "0..360" })", 2 * kPi, 0},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "0..360" })", 5 * kPi, 180},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "-180..180" })", kPi, -180},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "-180..180" })", -kPi, -180},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "deg", wrap = "-180..180" })", 1.5 * kPi, -90},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "rad", wrap = "0..2pi" })", -0.5,
                2 * kPi - 0.5},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "rad", wrap = "-pi..pi" })", 4.0,
                4.0 - 2 * kPi},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "rad", wrap = "none" })", 7.0, 7.0},
        WrapRow{R"({ type = "f64", offset = 0, from = "heading", unit = "cdeg", wrap = "0..360" })", -kPi, 18000},
        // integers: rounded, then wrapped again (359.6 deg is 360, is 0)
        WrapRow{R"({ type = "i32", offset = 0, from = "heading", unit = "deg", wrap = "0..360" })", 359.6 * kPi / 180,
                0},
        WrapRow{R"({ type = "i32", offset = 0, from = "heading", unit = "deg", wrap = "-180..180" })",
                179.7 * kPi / 180, -180},
        WrapRow{R"({ type = "i32", offset = 0, from = "heading", unit = "deg", wrap = "-180..180", add = -80 })", -kPi,
                100}));

TEST(Conversions, BoolsStoredAsTrueAndFalse) {
  One arm("CMD_INFO", "just_kicked", R"({ type = "u8", offset = 0, from = "just_kicked", true = 7, false = 3 })");
  arm.buf.set(arm.q, 1);
  EXPECT_EQ(arm.raw<std::uint8_t>(), 7);
  arm.buf.set(arm.q, 0);
  EXPECT_EQ(arm.raw<std::uint8_t>(), 3);
  EXPECT_EQ(arm.buf.get(arm.q), 0.0);
  arm.buf.bytes()[0] = std::byte{5};
  EXPECT_EQ(arm.buf.get(arm.q), 1.0) << "anything but false reads true";
  One flag("CMD_INFO", "just_kicked", R"({ type = "bool", offset = 0, from = "just_kicked" })");
  flag.buf.set(flag.q, 0.2);
  EXPECT_EQ(flag.raw<std::uint8_t>(), 1);
  flag.buf.set(flag.q, std::nan(""));
  EXPECT_EQ(flag.raw<std::uint8_t>(), 0);
  One plain("CMD_INFO", "just_kicked", R"({ type = "i32", offset = 0, from = "just_kicked" })");
  plain.buf.set(plain.q, 1);
  EXPECT_EQ(plain.raw<std::int32_t>(), 1) << "true = 1, false = 0 by default";
}

TEST(Conversions, EnumValues) {
  One gs("COACH_INFO", "game_state",
         R"({ type = "i16", offset = 0, from = "game_state", values = { start = 3, stop = 1 } })");
  gs.buf.set(gs.q, "start");
  EXPECT_EQ(gs.raw<std::int16_t>(), 3);
  EXPECT_EQ(gs.buf.get(gs.q), 3.0);
  EXPECT_EQ(gs.buf.get_enum(gs.q), "start");
  try {
    gs.buf.set(gs.q, "halt");
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_NE(std::string(e.what()).find("one.toml:3: COACH_INFO.f: no value for game_state 'halt' (this field gives "
                                         "stop, start)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(gs.raw<std::int16_t>(), 3) << "unchanged";
  gs.buf.set(gs.q, 7.0);
  EXPECT_EQ(gs.raw<std::int16_t>(), 7) << "a number is stored as it is";
  EXPECT_EQ(gs.buf.get_enum(gs.q), "") << "no name for 7";
}

TEST(Conversions, IntegersRoundToNearestOrTowardZero) {
  One near("CMD_INFO", "v_logic", R"({ type = "i16", offset = 0, from = "v_logic", unit = "V" })");
  for (const auto& [si, want] : {std::pair{2.5, 3}, {-2.5, -3}, {2.4999, 2}, {-0.4, 0}, {0.5, 1}}) {
    near.buf.set(near.q, si);
    EXPECT_EQ(near.raw<std::int16_t>(), want) << si;
  }
  One trunc("CMD_INFO", "v_logic", R"({ type = "i16", offset = 0, from = "v_logic", unit = "V", round = false })");
  for (const auto& [si, want] : {std::pair{2.9, 2}, {-2.9, -2}, {0.99, 0}}) {
    trunc.buf.set(trunc.q, si);
    EXPECT_EQ(trunc.raw<std::int16_t>(), want) << si;
  }
}

template <class T>
T stored(const char* type, double si) {
  One one("CMD_KICKER", "kick", std::string("{ type = \"") + type + "\", offset = 0, from = \"kick\" }");
  one.buf.set(one.q, si);
  return one.raw<T>();
}

TEST(Conversions, SaturateIntoTheFieldType) {
  EXPECT_EQ(stored<std::uint8_t>("u8", 300), 255);
  EXPECT_EQ(stored<std::uint8_t>("u8", -5), 0);
  EXPECT_EQ(stored<std::int8_t>("i8", 200), 127);
  EXPECT_EQ(stored<std::int8_t>("i8", -200), -128);
  EXPECT_EQ(stored<std::int16_t>("i16", 40000), 32767);
  EXPECT_EQ(stored<std::uint16_t>("u16", -1), 0);
  EXPECT_EQ(stored<std::uint16_t>("u16", 65535.4), 65535);
  EXPECT_EQ(stored<std::int32_t>("i32", 3e9), std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(stored<std::int32_t>("i32", -3e9), std::numeric_limits<std::int32_t>::min());
  EXPECT_EQ(stored<std::uint32_t>("u32", 5e9), std::numeric_limits<std::uint32_t>::max());
  EXPECT_EQ(stored<std::uint32_t>("u32", -1), 0u);
  EXPECT_EQ(stored<std::int64_t>("i64", 1e19), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(stored<std::int64_t>("i64", -1e19), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(stored<std::int64_t>("i64", -12345678901.0), -12345678901);
  EXPECT_EQ(stored<std::uint64_t>("u64", 2e19), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(stored<std::uint32_t>("u32", std::nan("")), 0u) << "NaN stores 0 in an integer";
  EXPECT_EQ(stored<std::int32_t>("i32", std::numeric_limits<double>::infinity()),
            std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(stored<float>("f32", 1e300), FLT_MAX);
  EXPECT_EQ(stored<float>("f32", -1e300), -FLT_MAX);
  EXPECT_TRUE(std::isnan(stored<float>("f32", std::nan(""))));
  EXPECT_EQ(stored<double>("f64", 1e300), 1e300);
}

TEST(Conversions, PerAgentArrays) {
  One base1("COACH_INFO", "running",
            R"({ type = "u8", offset = 0, count = 3, stride = 4, from = "running", index = "agent" })");
  base1.buf.set(base1.q, 1, 1);
  base1.buf.set(base1.q, 1, 3);
  base1.buf.set(base1.q, 1, 0);  // agent 0 is no robot here
  base1.buf.set(base1.q, 1, 4);  // past the array
  EXPECT_EQ(base1.raw<std::uint8_t>(0), 1);
  EXPECT_EQ(base1.raw<std::uint8_t>(4), 0);
  EXPECT_EQ(base1.raw<std::uint8_t>(8), 1);
  EXPECT_EQ(base1.buf.get(base1.q, 3), 1.0);
  EXPECT_EQ(base1.buf.get(base1.q, 4), 0.0);
  EXPECT_EQ(base1.layout.item("COACH_INFO")->capacity("running"), 3u);
  One base0("COACH_INFO", "running",
            R"({ type = "u8", offset = 0, count = 3, from = "running", index = "agent", index_base = 0 })");
  base0.buf.set(base0.q, 1, 0);
  EXPECT_EQ(base0.raw<std::uint8_t>(0), 1);
}

TEST(Conversions, PointListsTruncateToTheCapacityAndCountThem) {
  const Layout layout = Layout::parse(R"([VISION_INFO]
size = 24
n = { type = "i32", offset = 0, from = "lines.count" }
pts = { type = "i16", offset = 4, count = 2, stride = 8, components = 2, from = "lines", unit = "cm" }
)",
                                      "v.toml");
  ItemBuffer buf(*layout.item("VISION_INFO"));
  const std::array<std::array<double, 2>, 3> pts{{{1.0, -2.0}, {0.123, 0.456}, {9, 9}}};
  buf.set_points(buf.quantity("lines"), pts);
  std::int32_t n;
  std::memcpy(&n, buf.data(), 4);
  EXPECT_EQ(n, 2) << "three points, room for two";
  std::int16_t v[2];
  std::memcpy(v, buf.bytes().data() + 12, 4);
  EXPECT_EQ(v[0], 12);
  EXPECT_EQ(v[1], 46);
  EXPECT_EQ(buf.get_point(buf.quantity("lines"), 0)[1], -2.0);
  EXPECT_EQ(buf.get_point(buf.quantity("lines"), 2)[0], 0.0) << "past the capacity";
  EXPECT_EQ(buf.get(buf.quantity("lines.count")), 2.0);
}

TEST(Conversions, ConstantsAreWrittenByClear) {
  const Layout layout = Layout::parse(R"([COACH_INFO]
size = 16
goal = { type = "i32", offset = 0, count = 2, value = 1 }
flag = { type = "bool", offset = 8, value = true }
scale = { type = "f32", offset = 12, value = 0.5 }
)",
                                      "c.toml");
  ItemBuffer buf(*layout.item("COACH_INFO"));
  std::int32_t goal[2];
  std::memcpy(goal, buf.data(), 8);
  EXPECT_EQ(goal[0], 1);
  EXPECT_EQ(goal[1], 1);
  EXPECT_EQ(buf.bytes()[8], std::byte{1});
  std::fill(buf.bytes().begin(), buf.bytes().end(), std::byte{0xAA});
  buf.clear();
  std::memcpy(goal, buf.data(), 8);
  EXPECT_EQ(goal[1], 1);
  EXPECT_EQ(buf.bytes()[11], std::byte{0}) << "between the fields";
  float scale;
  std::memcpy(&scale, buf.bytes().data() + 12, 4);
  EXPECT_EQ(scale, 0.5f);
}

TEST(Conversions, AbsentQuantitiesWriteNothingAndReadZero) {
  One one("CMD_VEL", "vx", R"({ type = "f32", offset = 0, from = "vx", unit = "m/s" })");
  const Quantity vy = one.buf.quantity("vy");
  EXPECT_FALSE(vy);
  one.buf.set(vy, 3.0);
  EXPECT_EQ(one.buf.get(vy), 0.0);
  EXPECT_TRUE(
      std::all_of(one.buf.bytes().begin(), one.buf.bytes().end(), [](std::byte b) { return b == std::byte{0}; }));
  EXPECT_DEATH(one.buf.quantity("vz"), "outside canhil's contract") << "a misspelt name in canhil's code is a bug";
  const Layout other = Layout::parse("[ROBOT_WS]\nsize = 4\n", "r.toml");
  EXPECT_FALSE(ItemBuffer(*other.item("ROBOT_WS")).quantity("anything")) << "an item outside the contract";
}

#if CANHIL_COUNT_ALLOCATIONS
TEST(Conversions, NoAllocationOnTheSetGetPath) {
  const Layout layout = Layout::shipped("cambada");
  ItemBuffer vision(*layout.item("VISION_INFO"));
  ItemBuffer coach(*layout.item("COACH_INFO"));
  ItemBuffer imu(*layout.item("CMD_IMU"));
  const Quantity lines = vision.quantity("lines");
  const Quantity running = coach.quantity("running");
  const Quantity game = coach.quantity("game_state");
  const Quantity heading = imu.quantity("heading");
  std::vector<std::array<double, 2>> pts(600, {1.0, 2.0});
  const std::size_t before = g_allocations.load();
  double sum = 0;
  for (int i = 0; i < 100; ++i) {
    vision.clear();
    vision.set_points(lines, pts);
    sum += vision.get_point(lines, 3)[0];
    coach.set(running, 1, 2);
    coach.set(game, "start");
    sum += coach.get(running, 2) + static_cast<double>(coach.get_enum(game).size());
    imu.set(heading, i * 3.7);
    sum += imu.get(heading);
  }
  EXPECT_EQ(g_allocations.load(), before);
  EXPECT_TRUE(std::isfinite(sum));
}
#endif

}  // namespace
}  // namespace canhil::rtdb
