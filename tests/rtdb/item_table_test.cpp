// ItemTable: a team's rtdb_user.h and rtdb.ini read and checked against each
// other; every mistake named by file and line; canhil's linked table.
#include "canhil/rtdb/item_table.hpp"

#include <gtest/gtest.h>

#include "canhil/base/setup_error.hpp"
#include "canhil/rtdb/cambada_types.h"
#include "rtdb_user.h"
#include "support/error_of.hpp"
#include "support/team_rtdb.hpp"

namespace canhil::rtdb {
namespace {

using test::write_file;

using test::error_of;

TEST(ItemTable, ReadsTheTeamsHeaderAndIni) {
  const test::TeamFiles f = test::write_team_files("item_table_reads");
  const ItemTable t = ItemTable::from_files(f.user_h, f.ini);
  ASSERT_EQ(t.agent_count(), 3);
  EXPECT_EQ(t.agent_name(test::kRobot1), "ROBOT_1");
  EXPECT_EQ(t.agent("ROBOT_2"), 2);
  EXPECT_EQ(t.agent("ROBOT_3"), std::nullopt);
  EXPECT_EQ(t.item_count(), 6);
  EXPECT_EQ(t.id("VISION_INFO"), test::kVisionInfo);
  EXPECT_EQ(t.id("NO_SUCH_ITEM"), std::nullopt);
  EXPECT_EQ(t.size(test::kVisionInfo), 8052u);
  EXPECT_EQ(t.name(test::kCmdPos), "CMD_POS");
  EXPECT_EQ(t.kind(test::kBaseStation, test::kCoachInfo), ItemKind::kShared);
  EXPECT_EQ(t.kind(test::kRobot1, test::kCoachInfo), ItemKind::kLocal);
  EXPECT_EQ(t.kind(test::kBaseStation, test::kVisionInfo), ItemKind::kNone);
  EXPECT_EQ(t.kind(7, test::kVisionInfo), ItemKind::kNone);
  EXPECT_EQ(t.items_of(test::kRobot2, ItemKind::kShared), std::vector<int>{test::kRobotWs});
  EXPECT_EQ(t.items_of(test::kRobot2, ItemKind::kLocal), (std::vector<int>{1, 2, 3, 5}));
  // Declared in the header, in no agent's section: kept, without a size.
  EXPECT_EQ(t.name(test::kUnusedItem), "UNUSED_ITEM");
  EXPECT_EQ(t.size(test::kUnusedItem), std::nullopt);
  EXPECT_EQ(t.unconfigured(), std::vector<int>{test::kUnusedItem});
  EXPECT_EQ(t.source(), f.user_h.string() + " + " + f.ini.string());
}

TEST(ItemTable, AnIniAloneNamesItemsByNumber) {
  const test::TeamFiles f = test::write_team_files("item_table_ini_alone");
  const ItemTable t = ItemTable::from_ini(f.ini);
  EXPECT_EQ(t.name(test::kVisionInfo), "item2");
  EXPECT_EQ(t.id("item2"), test::kVisionInfo);
  EXPECT_EQ(t.agent_name(test::kRobot1), "ROBOT_1") << "agent names are in the ini";
  EXPECT_EQ(t.size(test::kUnusedItem), std::nullopt) << "an id the ini leaves out";
  EXPECT_TRUE(t.unconfigured().empty());
}

// The other half of an inconsistent pair (a header from a shorter
// configuration): an ini item the header does not name.
TEST(ItemTable, AnIniItemTheHeaderDoesNotNameIsNamed) {
  const test::TeamFiles f = test::write_team_files("item_table_unnamed");
  std::string header = test::team_user_h();
  header.replace(header.find("#define CMD_POS\t5\n"), 18, "");
  header.replace(header.find("N_ITEMS\t6"), 9, "N_ITEMS\t5");
  write_file(f.user_h, header);
  EXPECT_EQ(error_of([&] { ItemTable::from_files(f.user_h, f.ini); }),
            f.ini.string() + ":14: item 5 has no name in " + f.user_h.string() +
                "; the two files come from different configurations: use the rtdb_user.h and rtdb.ini of one run "
                "of the generator");
}

TEST(ItemTable, AgentsNumberedOtherwiseAreNamed) {
  const test::TeamFiles f = test::write_team_files("item_table_agents");
  std::string header = test::team_user_h();
  header.replace(header.find("ROBOT_1\t1"), 9, "ROBOT_1\t2");
  header.replace(header.find("ROBOT_2\t2"), 9, "ROBOT_2\t1");
  write_file(f.user_h, header);
  EXPECT_NE(error_of([&] {
              ItemTable::from_files(f.user_h, f.ini);
            }).find(f.user_h.string() + ":9: ROBOT_1 is agent 2 here but agent 1 in " + f.ini.string() + ":9"),
            std::string::npos);
}

struct BadFile {
  const char* name;
  const char* ini;     // nullptr: the team's
  const char* header;  // nullptr: the team's
  const char* file;    // "ini" or "header": where the error is
  const char* says;    // after "FILE:"
};

class BadTeamFiles : public ::testing::TestWithParam<BadFile> {};

TEST_P(BadTeamFiles, AreNamedByFileAndLine) {
  const BadFile& b = GetParam();
  const test::TeamFiles f = test::write_team_files(std::string("item_table_bad_") + b.name);
  if (b.ini != nullptr) write_file(f.ini, b.ini);
  if (b.header != nullptr) write_file(f.user_h, b.header);
  const std::string file = std::string(b.file) == "ini" ? f.ini.string() : f.user_h.string();
  const std::string error = error_of([&] { ItemTable::from_files(f.user_h, f.ini); });
  EXPECT_EQ(error.rfind(file + ":" + b.says, 0), 0u) << error;
}

INSTANTIATE_TEST_SUITE_P(
    Rows, BadTeamFiles,
    ::testing::Values(BadFile{"item_first", "1 64 1 s\n# 0 BASE_STATION\n", nullptr, "ini",
                              "1: an item before the first agent section (\"# 0 NAME\")"},
                      BadFile{"kind", "# 0 BASE_STATION\n1 64 1 shared\n", nullptr, "ini",
                              "2: item 1 is \"shared\"; write s (shared) or l (local)"},
                      BadFile{"order", "# 0 BASE_STATION\n1 64 1 s\n# 2 ROBOT_2\n", nullptr, "ini",
                              "3: this is agent 2's section, but agent 1's comes next"},
                      BadFile{"twice", "# 0 BASE_STATION\n1 64 1 s\n1 64 1 s\n", nullptr, "ini",
                              "3: item 1 is listed twice in agent BASE_STATION's section (first on line 2)"},
                      BadFile{"sizes", "# 0 BASE_STATION\n1 64 1 s\n# 1 ROBOT_1\n1 60 1 l\n", nullptr, "ini",
                              "4: item 1 is 60 bytes here but 64 bytes on line 2"},
                      BadFile{"range", "# 0 BASE_STATION\n100 4 1 s\n", nullptr, "ini",
                              "2: item id 100 is out of range"},
                      BadFile{"words", "# 0 BASE_STATION\n1 sixty-four 1 s\n", nullptr, "ini",
                              "2: expected an item line \"ID SIZE PERIOD s|l\""},
                      BadFile{"empty", "## nothing\n", nullptr, "ini", " no agent section"},
                      BadFile{"value", nullptr, "#define BASE_STATION 0\n#define ROBOT_1 one\n", "header",
                              "2: ROBOT_1's value is not a whole number"},
                      BadFile{"code", nullptr, "#define BASE_STATION 0\nint x;\n", "header",
                              "2: not a line of a generated rtdb_user.h (#define NAME NUMBER)"},
                      BadFile{"same_id", nullptr, "#define ROBOT_WS 0\n#define LAPTOP_INFO 0\n", "header",
                              "2: ROBOT_WS and LAPTOP_INFO both have id 0"},
                      BadFile{"n_agents", nullptr, "#define N_AGENTS 7\n", "header", "1: N_AGENTS is 7 but "}),
    [](const ::testing::TestParamInfo<BadFile>& row) { return std::string(row.param.name); });

TEST(ItemTable, AFileThatIsNotThereIsNamed) {
  const auto dir = test::scratch_dir("item_table_missing");
  EXPECT_EQ(error_of([&] { ItemTable::from_ini(dir / "rtdb.ini"); }),
            (dir / "rtdb.ini").string() + ": cannot read the item table (No such file or directory)");
}

TEST(ItemTable, BuiltinIsCanhilsLinkedConfiguration) {
  const ItemTable t = ItemTable::builtin();
  EXPECT_EQ(t.agent_count(), N_AGENTS);
  EXPECT_EQ(t.item_count(), N_ITEMS);
  EXPECT_EQ(t.id("CMD_VEL"), CMD_VEL);
  EXPECT_EQ(t.size(VISION_INFO), sizeof(VisionInfo));
  EXPECT_EQ(t.kind(CAMBADA_1, ROBOT_WS), ItemKind::kShared);
  EXPECT_EQ(t.agent_name(BASE_STATION), "BASE_STATION");
  EXPECT_NE(t.source().find("rtdb.conf"), std::string::npos) << t.source();
}

}  // namespace
}  // namespace canhil::rtdb
