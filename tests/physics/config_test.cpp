#include "canhil/physics/config.hpp"

#include <gtest/gtest.h>

#include "support/test_paths.hpp"

namespace canhil::physics {
namespace {

TEST(Config, ShippedFileListsExactlyTheDefaults) {
  const WorldParams shipped = load_world_params(test::source_dir() + "/physics/config/world.toml");
  EXPECT_TRUE(shipped == WorldParams{}) << "physics/config/world.toml and params.hpp disagree";
}

TEST(Config, EmptyFileGivesDefaultsAndPartialFilesOverride) {
  EXPECT_TRUE(parse_world_params("", "empty.toml") == WorldParams{});
  const WorldParams p = parse_world_params(R"(
[simulation]
exact_solver_max_rows = 100
[ball]
mass_kg = 0.45
[robot.kicker]
max_lob_range_m = 12
[[robots]]
x_m = 1.5
heading_deg = 90
[[robots]]
y_m = -2
[[obstacles]]
x_m = 3
movable = true
)",
                                           "partial.toml");
  EXPECT_EQ(p.simulation.exact_solver_max_rows, 100);
  EXPECT_EQ(p.ball.mass_kg, 0.45);
  EXPECT_EQ(p.ball.radius_m, 0.11) << "untouched fields keep their defaults";
  EXPECT_EQ(p.robot.kicker.max_lob_range_m, 12.0);
  ASSERT_EQ(p.robots.size(), 2u);
  EXPECT_EQ(p.robots[0].x_m, 1.5);
  EXPECT_EQ(p.robots[0].heading_deg, 90.0);
  EXPECT_EQ(p.robots[1].y_m, -2.0);
  ASSERT_EQ(p.obstacles.size(), 1u);
  EXPECT_TRUE(p.obstacles[0].params.movable);
}

struct Bad {
  const char* name;
  const char* text;
  int line;
  const char* field;
  const char* says;
};

class BadConfig : public ::testing::TestWithParam<Bad> {};

TEST_P(BadConfig, NamesFileLineFieldAndWhatToDo) {
  const Bad& b = GetParam();
  try {
    parse_world_params(b.text, "world.toml");
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "world.toml");
    EXPECT_EQ(e.line(), b.line) << e.what();
    EXPECT_EQ(e.field(), b.field) << e.what();
    EXPECT_NE(std::string(e.what()).find(b.says), std::string::npos) << e.what();
    const std::string prefix =
        "world.toml:" + std::to_string(b.line) + ": " + (b.field[0] ? std::string(b.field) + ": " : "");
    EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    EachKindOfMistake, BadConfig,
    ::testing::Values(
        Bad{"Misspelt", "[ball]\nmass_kg = 0.4\nradius = 0.11\n", 3, "ball.radius", "did you mean radius_m?"},
        Bad{"UnknownSection", "[balls]\nmass_kg = 1\n", 1, "balls", "unknown field"},
        Bad{"WrongType", "[ball]\n\nmass_kg = \"heavy\"\n", 3, "ball.mass_kg", "must be a number"},
        Bad{"Negative", "[ball]\nmass_kg = -1\n", 2, "ball.mass_kg", "must be greater than 0, got -1"},
        Bad{"OutOfRange", "[ball]\nrestitution = 1.5\n", 2, "ball.restitution", "must be between 0 and 1"},
        Bad{"NotAWholeNumber", "[simulation]\nsubsteps = 2.5\n", 2, "simulation.substeps", "whole number"},
        Bad{"NotABoolean", "[field]\nboundary = 1\n", 2, "field.boundary", "true or false"},
        Bad{"WrongList", "[robot]\nwheel_angles_deg = [30, 150]\n", 2, "robot.wheel_angles_deg", "list of 3 numbers"},
        Bad{"SectionNotATable", "ball = 3\n", 1, "ball", "must be a table"},
        Bad{"BadRobotEntry", "[[robots]]\nx_m = 1\n[[robots]]\nx_m = \"left\"\n", 4, "robots[1].x_m",
            "must be a number"},
        Bad{"MouthTooWide", "[robot]\nmouth_width_m = 0.6\n", 1, "robot.mouth_width_m",
            "less than the body's diameter"},
        Bad{"RailUpsideDown", "[robot.battery.logic]\nfull_v = 10\nempty_v = 11\n", 1, "robot.battery.logic.empty_v",
            "below full_v"},
        Bad{"NotToml", "[ball\nmass_kg = 1\n", 1, "", "not valid TOML"}),
    [](const ::testing::TestParamInfo<Bad>& p) { return std::string(p.param.name); });

TEST(Config, MissingFileIsNamed) {
  try {
    load_world_params("/nonexistent/world.toml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/world.toml: cannot read"), std::string::npos);
  }
}

}  // namespace
}  // namespace canhil::physics
