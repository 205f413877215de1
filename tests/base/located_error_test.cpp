// The one located set-up error (base/located_error.hpp) every file reader
// throws under its own name: `FILE:LINE: FIELD: message`.
#include "canhil/base/located_error.hpp"

#include <gtest/gtest.h>

#include <string>

namespace canhil {
namespace {

struct Row {
  const char* file;
  int line;
  const char* field;
  const char* message;
  const char* what;
};

TEST(LocatedError, TextNamesFileLineAndFieldWhenKnown) {
  const Row rows[] = {
      {"world.toml", 12, "ball.mass_kg", "must be greater than 0, got -1",
       "world.toml:12: ball.mass_kg: must be greater than 0, got -1"},
      {"robot.dbc", 7, "", "unknown keyword", "robot.dbc:7: unknown keyword"},
      {"team.toml", 0, "VISION_INFO.ball", "missing", "team.toml: VISION_INFO.ball: missing"},
      {"/nonexistent/rtdb.conf", 0, "", "cannot read", "/nonexistent/rtdb.conf: cannot read"},
  };
  for (const Row& r : rows) {
    const LocatedError e(r.file, r.line, r.field, r.message);
    EXPECT_STREQ(e.what(), r.what);
    EXPECT_EQ(e.file(), r.file);
    EXPECT_EQ(e.line(), r.line);
    EXPECT_EQ(e.field(), r.field);
  }
}

TEST(LocatedError, IsASetupError) {
  try {
    throw LocatedError("a.toml", 3, "", "bad");
  } catch (const SetupError& e) {
    EXPECT_EQ(std::string(e.what()), "a.toml:3: bad");
  }
}

}  // namespace
}  // namespace canhil
