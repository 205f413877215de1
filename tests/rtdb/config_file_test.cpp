#include "canhil/rtdb/config_file.hpp"

#include <gtest/gtest.h>

#include "support/test_paths.hpp"

namespace canhil::rtdb {
namespace {

TEST(RtdbConfig, ShippedFileParses) {
  const RtdbConfig c = load_rtdb_config(test::source_dir() + "/rtdb/config/rtdb.conf");
  ASSERT_EQ(c.agents.size(), 7u);
  EXPECT_EQ(c.agents[0], "BASE_STATION");
  EXPECT_EQ(c.items.size(), 12u);
  EXPECT_EQ(c.items[0].name, "ROBOT_WS");
  EXPECT_EQ(c.membership[1][0], 1) << "ROBOT_WS shared by players";
  EXPECT_EQ(c.membership[0][0], -1) << "not in the base station's schema";
  const std::string header = generate_user_header(c);
  EXPECT_NE(header.find("#define CMD_VEL 3"), std::string::npos);
  EXPECT_NE(header.find("#define N_AGENTS 7"), std::string::npos);
  const std::string source = generate_config_source(c);
  EXPECT_NE(source.find("sizeof(VisionInfo)"), std::string::npos);
}

TEST(RtdbConfig, DefaultsForHeaderAndPeriod) {
  const RtdbConfig c = parse_rtdb_config(
      "AGENTS = A;\nITEM X { datatype = Foo; }\nSCHEMA S { local = X; }\nASSIGNMENT { schema = S; agents = A; }\n",
      "t.conf");
  EXPECT_EQ(c.items[0].headerfile, "Foo.h");
  EXPECT_EQ(c.items[0].period, 1);
}

struct Bad {
  const char* name;
  const char* text;
  int line;
  const char* says;
};

class BadRtdbConfig : public ::testing::TestWithParam<Bad> {};

TEST_P(BadRtdbConfig, NamesTheLineAndWhatToDo) {
  try {
    parse_rtdb_config(GetParam().text, "rtdb.conf");
    FAIL() << "accepted";
  } catch (const RtdbConfigError& e) {
    EXPECT_EQ(e.line(), GetParam().line) << e.what();
    EXPECT_NE(std::string(e.what()).find(GetParam().says), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("rtdb.conf:" + std::to_string(GetParam().line) + ": ", 0), 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(
    EachKindOfMistake, BadRtdbConfig,
    ::testing::Values(
        Bad{"NoAgents", "ITEM X { datatype = T; }\n", 1, "no AGENTS list"},
        Bad{"DuplicateAgent", "AGENTS = A, A;\n", 1, "listed twice"},
        Bad{"NoDatatype", "AGENTS = A;\nITEM X { period = 2; }\n", 2, "has no datatype"},
        Bad{"BadPeriod", "AGENTS = A;\nITEM X { datatype = T;\n period = 0; }\n", 3, "period of X"},
        Bad{"UnknownItemField", "AGENTS = A;\nITEM X { datatype = T; size = 4; }\n", 2, "unknown item field"},
        Bad{"DuplicateItem", "AGENTS = A;\nITEM X { datatype = T; }\nITEM X { datatype = T; }\n", 3, "declared twice"},
        Bad{"SchemaNamesUnknownItem", "AGENTS = A;\nITEM X { datatype = T; }\nSCHEMA S { local = Y; }\n", 3,
            "names item Y, which no ITEM declares"},
        Bad{"ItemTwiceInSchema", "AGENTS = A;\nITEM X { datatype = T; }\nSCHEMA S { shared = X; local = X; }\n", 3,
            "lists item X twice"},
        Bad{"UnknownSchema", "AGENTS = A;\nITEM X { datatype = T; }\nASSIGNMENT { schema = Q; agents = A; }\n", 3,
            "names schema Q"},
        Bad{"UnknownAgent",
            "AGENTS = A;\nITEM X { datatype = T; }\nSCHEMA S { local = X; }\nASSIGNMENT { schema = S; agents = B; }\n",
            4, "names agent B"},
        Bad{"Unassigned",
            "AGENTS = A, B;\nITEM X { datatype = T; }\nSCHEMA S { local = X; }\nASSIGNMENT { schema = S; agents = A; "
            "}\n",
            1, "agent B has no ASSIGNMENT"},
        Bad{"MissingBrace", "AGENTS = A;\nITEM X datatype = T; }\n", 2, "expected '{'"},
        Bad{"UnknownSection", "AGENTS = A;\nITEMS X { datatype = T; }\n", 2, "unknown section"},
        Bad{"StrayCharacter", "AGENTS = A;\nITEM X { datatype = T*; }\n", 2, "unexpected character '*'"}),
    [](const ::testing::TestParamInfo<Bad>& p) { return std::string(p.param.name); });

TEST(RtdbConfig, MissingFile) {
  try {
    load_rtdb_config("/nonexistent/rtdb.conf");
    FAIL() << "no error";
  } catch (const RtdbConfigError& e) {
    EXPECT_EQ(e.line(), 0);
    EXPECT_STREQ(e.what(), "/nonexistent/rtdb.conf: cannot read the RTDB configuration (does it exist?)")
        << "the file as a whole: no line";
  }
}

}  // namespace
}  // namespace canhil::rtdb
