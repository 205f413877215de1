// Reading descriptions: what a well-formed one gives, and every kind of
// mistake named as `FILE:LINE: ITEM.FIELD: what is wrong; what to do`; the
// checks a user of a layout calls (require, check_size).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "canhil/rtdb/layout.hpp"
#include "support/test_paths.hpp"

namespace canhil::rtdb {
namespace {

TEST(LayoutParse, ReadsItemsFieldsAndDefaults) {
  const Layout layout = Layout::parse(R"(# a team's layout
[layout]
name = "team"
description = "ours"

[CMD_POS]
size = 24
deltas_frame = "robot"
px = { type = "f32", offset = 0, from = "x", unit = "m" }
dx = { type = "i16", offset = 4, from = "dx", unit = "mm", round = false }

[COACH_INFO]
size = 64
player.running = { type = "bool", offset = 1, count = 4, stride = 8, from = "running", index = "agent" }
player.role = { type = "u8", offset = 0, count = 4, stride = 8, from = "role", index = "agent", values = { striker = 3 } }

[SOMETHING_ELSE]
size = 3
)",
                                      "team.toml");
  EXPECT_EQ(layout.name(), "team");
  EXPECT_EQ(layout.description(), "ours");
  EXPECT_EQ(layout.file(), "team.toml");
  EXPECT_EQ(layout.items(), (std::vector<std::string>{"CMD_POS", "COACH_INFO", "SOMETHING_ELSE"}));
  EXPECT_EQ(layout.item("CMD_VEL"), nullptr);
  const ItemLayout& pos = *layout.item("CMD_POS");
  EXPECT_EQ(pos.size_bytes(), 24u);
  EXPECT_EQ(pos.line(), 6);
  EXPECT_EQ(pos.deltas_frame(), DeltasFrame::kRobot);
  ASSERT_EQ(pos.fields().size(), 2u);
  const FieldLayout& dx = *pos.field("dx");
  EXPECT_EQ(dx.line, 10);
  EXPECT_EQ(dx.type, ScalarType::kI16);
  EXPECT_EQ(dx.stride_bytes, 2u);
  EXPECT_EQ(dx.unit, "mm");
  EXPECT_EQ(dx.rounding, Rounding::kTowardZero);
  EXPECT_EQ(dx.stored_per_si, 1000.0);
  EXPECT_EQ(pos.quantities(), (std::vector<std::string_view>{"x", "dx"}));
  const ItemLayout& coach = *layout.item("COACH_INFO");
  ASSERT_NE(coach.field("player.role"), nullptr) << "a dotted key is a member of a struct";
  EXPECT_EQ(coach.fields()[0].name, "player.running") << "file order";
  EXPECT_EQ(coach.capacity("running"), 4u);
  EXPECT_TRUE(layout.item("SOMETHING_ELSE")->fields().empty());
  EXPECT_EQ(Layout::parse("[CMD_VEL]\nsize = 16\n", "dir/my_team.toml").name(), "my_team") << "named after its file";
}

struct Bad {
  const char* name;
  const char* text;
  int line;
  const char* where;
  const char* says;
};

class BadLayout : public ::testing::TestWithParam<Bad> {};

TEST_P(BadLayout, NamesTheFileLineAndField) {
  const Bad& b = GetParam();
  try {
    Layout::parse(b.text, "bad.toml");
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    const std::string what = e.what();
    const std::string prefix = "bad.toml:" + std::to_string(b.line) + ": " + b.where + ": ";
    EXPECT_EQ(what.rfind(prefix, 0), 0u) << what;
    EXPECT_NE(what.find(b.says), std::string::npos) << what;
    EXPECT_EQ(e.line(), b.line);
    EXPECT_EQ(e.field(), b.where);
  }
}

#define VEL "[CMD_VEL]\nsize = 16\n"
INSTANTIATE_TEST_SUITE_P(
    EachKindOfMistake, BadLayout,
    ::testing::Values(
        Bad{"UnknownType", VEL "vx = { type = \"float\", offset = 0, from = \"vx\", unit = \"m/s\" }\n", 3,
            "CMD_VEL.vx", "unknown type float; the types are i8, u8"},
        Bad{"UnknownUnit", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"km/h\" }\n", 3, "CMD_VEL.vx",
            "unknown unit km/h;"},
        Bad{"UnknownQuantity", VEL "vx = { type = \"f32\", offset = 0, from = \"vxx\", unit = \"m/s\" }\n", 3,
            "CMD_VEL.vx",
            "unknown quantity vxx; Did you mean vx? CMD_VEL's quantities are vx, vy, va, small_adjustment"},
        Bad{"QuantityOfAnotherItem", VEL "v = { type = \"f32\", offset = 0, from = \"v_logic\", unit = \"V\" }\n", 3,
            "CMD_VEL.v", "v_logic is a quantity of CMD_INFO"},
        Bad{"PastTheSize",
            "[CMD_VEL]\nsize = 4\nvx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\" }\n"
            "vy = { type = \"f32\", offset = 4, from = \"vy\", unit = \"m/s\" }\n",
            4, "CMD_VEL.vy", "ends at byte 8, past the item's size 4"},
        Bad{"Overlap",
            VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\" }\n"
                "vy = { type = \"f32\", offset = 2, from = \"vy\", unit = \"m/s\" }\n",
            4, "CMD_VEL.vy", "bytes 2..5 overlap vx (line 3, bytes 0..3)"},
        Bad{"OverlapInAnArrayOfStructs",
            "[COACH_INFO]\nsize = 24\na = { type = \"u32\", offset = 0, count = 3, stride = 8 }\n"
            "b = { type = \"u8\", offset = 16 }\n",
            4, "COACH_INFO.b", "bytes 16..16 overlap a (line 3, bytes 16..19)"},
        Bad{"NotANumberValue", VEL "x = { type = \"f32\", offset = 0, value = nan }\n", 3, "CMD_VEL.x",
            "value must be a number"},
        Bad{"CountTimesStridePastTheSize",
            "[VISION_INFO]\nsize = 40\nn = { type = \"i32\", offset = 0, from = \"lines.count\" }\n"
            "p = { type = \"f32\", offset = 4, count = 5, stride = 8, components = 2, from = \"lines\", unit = \"m\" "
            "}\n",
            4, "VISION_INFO.p", "ends at byte 44 (offset 4 + (count - 1) x stride 8 + 8), past the item's size 40"},
        Bad{"MissingType", VEL "vx = { offset = 0, from = \"vx\", unit = \"m/s\" }\n", 3, "CMD_VEL.vx", "missing type"},
        Bad{"MissingOffset", VEL "vx = { type = \"f32\", from = \"vx\", unit = \"m/s\" }\n", 3, "CMD_VEL.vx",
            "missing offset"},
        Bad{"NegativeOffset", VEL "vx = { type = \"f32\", offset = -4, from = \"vx\", unit = \"m/s\" }\n", 3,
            "CMD_VEL.vx", "offset must be between 0 and"},
        Bad{"EnumValueNotAnInteger",
            "[COACH_INFO]\nsize = 4\ngs = { type = \"i32\", offset = 0, from = \"game_state\", values = { start = "
            "\"3\" } }\n",
            3, "COACH_INFO.gs", "values: start must be a whole number"},
        Bad{"EnumNameUnknown",
            "[COACH_INFO]\nsize = 4\ngs = { type = \"i32\", offset = 0, from = \"game_state\", values = { strat = 3 } "
            "}\n",
            3, "COACH_INFO.gs", "strat is not a value of game_state; Did you mean start?"},
        Bad{"TomlSyntax", VEL "vx = { type = \"f32\", offset = 0,, from = \"vx\" }\n", 3, "CMD_VEL.vx",
            "not valid TOML"},
        Bad{"UnknownKey", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", units = \"m/s\" }\n", 3, "CMD_VEL.vx",
            "unknown key units; Did you mean unit?"},
        Bad{"UnitOfAnotherDimension", VEL "va = { type = \"f32\", offset = 8, from = \"va\", unit = \"mm\" }\n", 3,
            "CMD_VEL.va", "unit mm is a length but va is an angular speed; use one of rad/s, mrad/s, deg/s"},
        Bad{"TimeUnitOnALength", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"ms\" }\n", 3,
            "CMD_VEL.vx", "unit ms is a time"},
        Bad{"MissingUnit", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\" }\n", 3, "CMD_VEL.vx",
            "missing unit; vx is a speed"},
        Bad{"QuantityOutsideTheContract", "[ROBOT_WS]\nsize = 20\nx = { type = \"f32\", offset = 0, from = \"x\" }\n",
            3, "ROBOT_WS.x", "canhil reads and writes no quantity in ROBOT_WS"},
        Bad{"FromAndValue", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", value = 1 }\n", 3, "CMD_VEL.vx",
            "from (a quantity) or value (a constant), not both"},
        Bad{"ValueDoesNotFit", VEL "k = { type = \"u8\", offset = 0, value = 300 }\n", 3, "CMD_VEL.k",
            "value must be a whole number that fits u8"},
        Bad{"PerAgentWithoutIndex",
            "[COACH_INFO]\nsize = 8\nr = { type = \"bool\", offset = 0, count = 6, from = \"running\" }\n", 3,
            "COACH_INFO.r", "running is per agent: give index = \"agent\""},
        Bad{"WrapOnASpeed",
            VEL "va = { type = \"f32\", offset = 8, from = \"va\", unit = \"rad/s\", wrap = \"0..360\" }\n", 3,
            "CMD_VEL.va", "wrap applies to angles"},
        Bad{"BadWrap",
            "[CMD_POS]\nsize = 24\npa = { type = \"f32\", offset = 8, from = \"heading\", unit = \"rad\", "
            "wrap = \"0..180\" }\n",
            3, "CMD_POS.pa", "wrap must be \"none\""},
        Bad{"DirectionOnALength",
            VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\", direction = "
                "\"cw\" }\n",
            3, "CMD_VEL.vx", "direction applies to angles"},
        Bad{"PointsNeedTwoComponents",
            "[VISION_INFO]\nsize = 40\np = { type = \"f32\", offset = 0, count = 5, from = \"lines\", unit = \"m\" }\n",
            3, "VISION_INFO.p", "components = 2"},
        Bad{"CountWithoutList", "[VISION_INFO]\nsize = 4\nn = { type = \"i32\", offset = 0, from = \"lines.count\" }\n",
            3, "VISION_INFO.n", "lines.count without a field for lines"},
        Bad{"RoundOnAFloat", VEL "vx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\", round = true }\n",
            3, "CMD_VEL.vx", "round applies to integer types"},
        Bad{"UnitWithoutFrom", VEL "vx = { type = \"f32\", offset = 0, unit = \"m/s\" }\n", 3, "CMD_VEL.vx",
            "unit has no meaning without from"},
        Bad{"DeltasFrameElsewhere", VEL "deltas_frame = \"robot\"\n", 3, "CMD_VEL", "a setting of CMD_POS only"},
        Bad{"ItemKeyMisspelt", VEL "sise = 16\n", 3, "CMD_VEL.sise", "unknown key; Did you mean size?"},
        Bad{"MissingSize", "[CMD_VEL]\nvx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\" }\n", 1,
            "CMD_VEL", "missing size"}),
    [](const ::testing::TestParamInfo<Bad>& row) { return std::string(row.param.name); });
#undef VEL

TEST(LayoutParse, MissingFileSaysSo) {
  try {
    Layout::load("/nonexistent/team.toml");
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/team.toml: cannot read", 0), 0u) << e.what();
  }
}

TEST(LayoutParse, RequireNamesTheItemAndQuantity) {
  const Layout layout = Layout::parse(
      "[CMD_VEL]\nsize = 16\nvx = { type = \"f32\", offset = 0, from = \"vx\", unit = \"m/s\" }\n", "t.toml");
  EXPECT_EQ(&require(layout, "CMD_VEL", {"vx"}), layout.item("CMD_VEL"));
  try {
    require(layout, "CMD_VEL", {"vx", "vy"});
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.toml:1: CMD_VEL.vy: layout t has no field for this quantity", 0), 0u)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("add a field with from = \"vy\" to [CMD_VEL]"), std::string::npos);
  }
  try {
    require(layout, "CMD_INFO", {"v_logic"});
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.toml: CMD_INFO: layout t does not describe this item", 0), 0u) << e.what();
  }
  EXPECT_NO_THROW(check_size(layout, *layout.item("CMD_VEL"), 16));
  try {
    check_size(layout, *layout.item("CMD_VEL"), 12);
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_NE(std::string(e.what()).find("the RTDB's item is 12 bytes but layout t says size = 16"), std::string::npos)
        << e.what();
  }
}

TEST(LayoutParse, TheContractIsConsistent) {
  for (const QuantityInfo& q : contract()) {
    EXPECT_EQ(find_quantity(q.item, q.name), &q);
    if (q.kind == QuantityKind::kEnum) {
      EXPECT_GE(q.names.size(), 2u);
    }
  }
  EXPECT_EQ(find_quantity("CMD_VEL", "lines"), nullptr);
}

// docs/layouts.md's worked example does what the page says.
TEST(LayoutParse, TheDocsWorkedExample) {
  std::ifstream in(test::source_dir() + "/docs/layouts.md");
  std::stringstream page;
  page << in.rdbuf();
  const std::string text = page.str();
  const std::size_t name = text.find("name = \"our_team\"");
  ASSERT_NE(name, std::string::npos);
  const std::size_t begin = text.rfind("```toml\n", name) + 8;
  const std::string toml = text.substr(begin, text.find("\n```", name) - begin + 1);
  const Layout layout = Layout::parse(toml, "our_team.toml");

  ItemBuffer vel(*layout.item("CMD_VEL"));
  vel.set(vel.quantity("va"), 0.5);
  std::int16_t w;
  std::memcpy(&w, vel.bytes().data() + 4, 2);
  EXPECT_EQ(w, -500);
  ItemBuffer imu(*layout.item("CMD_IMU"));
  imu.set(imu.quantity("heading"), 30);
  std::uint16_t heading;
  std::memcpy(&heading, imu.data(), 2);
  EXPECT_EQ(heading, 6000);
  ItemBuffer coach(*layout.item("COACH_INFO"));
  coach.set(coach.quantity("running"), 1, 3);
  EXPECT_EQ(coach.bytes()[3], std::byte{1});
  EXPECT_THROW(coach.set(coach.quantity("game_state"), "ready"), LayoutError);
  ItemBuffer vision(*layout.item("VISION_INFO"));
  const std::vector<std::array<double, 2>> points(400, {1.234, -0.5});
  vision.set_points(vision.quantity("lines"), points);
  std::int32_t n;
  std::int16_t first[2];
  std::memcpy(&n, vision.data(), 4);
  std::memcpy(first, vision.bytes().data() + 4, 4);
  EXPECT_EQ(n, 250);
  EXPECT_EQ(first[0], 123);
  EXPECT_EQ(first[1], -50);
  EXPECT_FALSE(vision.quantity("balls"));

  std::string wrong = toml;
  const std::size_t unit = wrong.find("unit = \"mrad/s\"");
  wrong.replace(unit, 15, "unit = \"mrad\"");
  try {
    Layout::parse(wrong, "our_team.toml");
    FAIL() << "accepted";
  } catch (const LayoutError& e) {
    EXPECT_NE(text.find(std::string("    ") + e.what() + "\n"), std::string::npos) << "the page quotes " << e.what();
  }
}

}  // namespace
}  // namespace canhil::rtdb
