#include "canhil/frames/dbc.hpp"

#include <gtest/gtest.h>

#include "support/test_paths.hpp"

namespace canhil::frames {
namespace {

TEST(ShippedDbc, HasTheWholeContract) {
  const Database db = load_dbc(test::shipped_dbc());
  const std::vector<std::pair<std::string, std::uint32_t>> expected = {
      {"TM", 0x010},   {"M1", 0x100},   {"M3_1", 0x111}, {"M3_2", 0x112}, {"M3_3", 0x113}, {"M4_1", 0x121},
      {"M4_2", 0x122}, {"M6_1", 0x131}, {"M6_2", 0x132}, {"M8", 0x141},   {"M9", 0x151},   {"M5_1", 0x0A1},
      {"M5_2", 0x0A2}, {"M7", 0x0B0},   {"M2", 0x200},   {"M10", 0x210}};
  ASSERT_EQ(db.messages.size(), expected.size());
  for (const auto& [name, id] : expected) {
    const MessageDef* m = db.find_message(name);
    ASSERT_NE(m, nullptr) << name;
    EXPECT_EQ(m->id, id) << name;
    EXPECT_FALSE(m->extended);
    EXPECT_EQ(m->length, 8) << name;
    EXPECT_FALSE(m->transmitter.empty()) << name;
    EXPECT_FALSE(m->receivers().empty()) << name;
  }
  const MessageDef* m6 = db.find_message("M6_1");
  const SignalDef* vx = m6->find_signal("vx");
  ASSERT_NE(vx, nullptr);
  EXPECT_EQ(vx->start_bit, 0);
  EXPECT_EQ(vx->length, 16);
  EXPECT_EQ(vx->value_type, ValueType::kSigned);
  EXPECT_EQ(vx->byte_order, ByteOrder::kIntel);
  EXPECT_DOUBLE_EQ(vx->factor, 0.001);
  EXPECT_EQ(vx->unit, "m/s");
  EXPECT_EQ(m6->attribute_text("FttKind"), "sync");
  EXPECT_EQ(m6->attribute_int("GenMsgCycleTime"), 30);
  EXPECT_EQ(m6->attribute_int("FttIndex"), 6);
  EXPECT_EQ(db.find_message("M7")->attribute_text("FttKind"), "async");
  EXPECT_EQ(db.find_message("M7")->attribute_int("GenMsgDelayTime"), 1000);
  EXPECT_EQ(db.find_message("M1")->find_signal("enable")->value_names.at(0), "brake");
}

TEST(ParseDbc, AcceptsCommentsStringsAcrossLinesAndUnusedSections) {
  const Database db = parse_dbc(R"(VERSION "x"
NS_ :
	CM_
	BA_DEF_
BS_: 500 : 12,34
BU_: A B
VAL_TABLE_ T 1 "one" 0 "zero" ;
BO_ 100 MSG: 2 A
 SG_ s : 0|16@1+ (2,1) [1|131071] "u" B,A
EV_ E: 0 [0|0] "" 0 1 DUMMY_NODE_VECTOR0 Vector__XXX;
CM_ SG_ 100 s "two
lines";
// a comment line
BO_TX_BU_ 100 : A,B;
)",
                                "ok.dbc");
  ASSERT_EQ(db.messages.size(), 1u);
  const SignalDef& s = db.messages[0].signals[0];
  EXPECT_EQ(s.comment, "two\nlines");
  EXPECT_EQ(s.receivers, (std::vector<std::string>{"B", "A"}));
  EXPECT_EQ(db.messages[0].extra_transmitters, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(db.nodes, (std::vector<std::string>{"A", "B"}));
}

struct BadCase {
  const char* name;
  const char* text;
  int line;
  const char* says;
};

const char* const kHead = "VERSION \"\"\nBU_: A B\n";  // two lines

class MalformedDbc : public ::testing::TestWithParam<BadCase> {};

TEST_P(MalformedDbc, IsRejectedWithFileLineAndReason) {
  const BadCase& c = GetParam();
  try {
    parse_dbc(std::string(kHead) + c.text, "bad.dbc");
    FAIL() << "accepted: " << c.text;
  } catch (const DbcError& e) {
    EXPECT_EQ(e.file(), "bad.dbc");
    EXPECT_EQ(e.line(), c.line) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("bad.dbc:" + std::to_string(c.line) + ": ", 0), 0u) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    EachKindOfMistake, MalformedDbc,
    ::testing::Values(
        BadCase{"SignalOutsideMessage", "BO_ 1 M: 2 A\n SG_ s : 8|16@1+ (1,0) [0|0] \"\" B\n", 4,
                "runs past the 2-byte"},
        BadCase{"SignalBeforeMessage", " SG_ s : 0|8@1+ (1,0) [0|0] \"\" B\n", 3, "outside a message"},
        BadCase{"DuplicateId", "BO_ 1 M: 8 A\nBO_ 1 N: 8 A\n", 4, "reuses id"},
        BadCase{"DuplicateMessageName", "BO_ 1 M: 8 A\nBO_ 2 M: 8 A\n", 4, "used twice"},
        BadCase{"DuplicateSignal",
                "BO_ 1 M: 8 A\n SG_ s : 0|8@1+ (1,0) [0|0] \"\" B\n SG_ s : 8|8@1+ (1,0) [0|0] \"\" B\n", 5,
                "appears twice"},
        BadCase{"OverlappingSignals",
                "BO_ 1 M: 8 A\n SG_ a : 0|8@1+ (1,0) [0|0] \"\" B\n SG_ b : 4|8@1+ (1,0) [0|0] \"\" B\n", 5,
                "overlap at bit 4"},
        BadCase{"ZeroLength", "BO_ 1 M: 8 A\n SG_ s : 0|0@1+ (1,0) [0|0] \"\" B\n", 4, "use 1 to 64 bits"},
        BadCase{"TooLong", "BO_ 1 M: 8 A\n SG_ s : 0|65@1+ (1,0) [0|0] \"\" B\n", 4, "use 1 to 64 bits"},
        BadCase{"CanFdLength", "BO_ 1 M: 64 A\n", 3, "at most 8"},
        BadCase{"StandardIdTooLarge", "BO_ 2048 M: 8 A\n", 3, "above 0x7FF"},
        BadCase{"ZeroFactor", "BO_ 1 M: 8 A\n SG_ s : 0|8@1+ (0,0) [0|0] \"\" B\n", 4, "factor 0"},
        BadCase{"RangeOutsideTheBits", "BO_ 1 M: 8 A\n SG_ s : 0|32@1- (1,3.3e68) [-2147483648|2147483647] \"\" B\n", 4,
                "lies outside what its 32 signed bits can hold"},
        BadCase{"RangeBelowUnsignedBits", "BO_ 1 M: 8 A\n SG_ s : 0|8@1+ (0.5,10) [-20|5] \"\" B\n", 4,
                "fix the factor, the offset or the range"},
        BadCase{"MinAboveMax", "BO_ 1 M: 8 A\n SG_ s : 0|8@1+ (1,0) [5|1] \"\" B\n", 4, "minimum above maximum"},
        BadCase{"BadByteOrder", "BO_ 1 M: 8 A\n SG_ s : 0|8@2+ (1,0) [0|0] \"\" B\n", 4, "byte order"},
        BadCase{"MissingSign", "BO_ 1 M: 8 A\n SG_ s : 0|8@1 (1,0) [0|0] \"\" B\n", 4, "'+' (unsigned)"},
        BadCase{"NotANumber", "BO_ 1 M: 8 A\n SG_ s : 0|8@1+ (one,0) [0|0] \"\" B\n", 4, "number for the factor"},
        BadCase{"MissingColon", "BO_ 1 M 8 A\n", 3, "expected ':'"},
        BadCase{"Multiplexed", "BO_ 1 M: 8 A\n SG_ s m1 : 0|8@1+ (1,0) [0|0] \"\" B\n", 4, "multiplexed"},
        BadCase{"UnterminatedString", "BO_ 1 M: 8 A\nCM_ BO_ 1 \"never closed;\n\n", 4, "never closed"},
        BadCase{"CommentOnUnknownMessage", "CM_ BO_ 7 \"x\";\n", 3, "no message with id 7"},
        BadCase{"ValueTableOnUnknownSignal", "BO_ 1 M: 8 A\nVAL_ 1 nope 0 \"x\" ;\n", 4, "has no signal nope"},
        BadCase{"UndefinedAttribute", "BO_ 1 M: 8 A\nBA_ \"Nope\" BO_ 1 3;\n", 4, "never defined"},
        BadCase{"AttributeOutOfRange", "BO_ 1 M: 8 A\nBA_DEF_ BO_ \"P\" INT 0 100;\nBA_ \"P\" BO_ 1 300;\n", 5,
                "outside its range"},
        BadCase{"AttributeOutsideAHugeRange",
                "BO_ 1 M: 8 A\nBA_DEF_ BO_ \"P\" INT 99995555555555555555555555555 1e60;\nBA_ \"P\" BO_ 1 3;\n", 5,
                "outside its range [9.99956e+28, 1e+60]"},
        BadCase{"UnknownEnumValue", "BO_ 1 M: 8 A\nBA_DEF_ BO_ \"K\" ENUM \"a\",\"b\";\nBA_ \"K\" BO_ 1 \"c\";\n", 5,
                "use one of: a, b"},
        BadCase{"AttributeOnWrongObject", "BO_ 1 M: 8 A\nBA_DEF_ SG_ \"S\" INT 0 9;\nBA_ \"S\" BO_ 1 3;\n", 5,
                "another kind of object"},
        BadCase{"FloatOfWrongLength", "BO_ 1 M: 8 A\n SG_ s : 0|16@1- (1,0) [0|0] \"\" B\nSIG_VALTYPE_ 1 s : 1;\n", 5,
                "make it 32 bits"},
        BadCase{"MissingSemicolon", "BO_ 1 M: 8 A\nBA_DEF_ BO_ \"P\" INT 0 100\nBA_ \"P\" BO_ 1 3;\n", 5,
                "expected ';'"},
        BadCase{"UnknownKeyword", "BOO_ 1 M: 8 A\n", 3, "unknown section keyword"}),
    [](const ::testing::TestParamInfo<BadCase>& p) { return std::string(p.param.name); });

TEST(LoadDbc, MissingFileSaysWhatToDo) {
  try {
    load_dbc("/nonexistent/robot.dbc");
    FAIL();
  } catch (const DbcError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/robot.dbc");
    EXPECT_NE(std::string(e.what()).find("--dbc"), std::string::npos);
  }
}

}  // namespace
}  // namespace canhil::frames
