#include "canhil/frames/describe.hpp"

#include <gtest/gtest.h>

#include "canhil/frames/candump.hpp"
#include "support/test_paths.hpp"

namespace canhil::frames {
namespace {

std::string text_of(const Codec& c, const char* compact) {
  CanFrame f;
  EXPECT_TRUE(parse_compact(compact, f));
  return describe_text(f, describe(c, f));
}

TEST(Describe, TextShowsNamesValuesUnitsAndProblems) {
  const Codec c(load_dbc(test::shipped_dbc()));
  EXPECT_EQ(text_of(c, "131#F401000000000000"), "M6_1  vx=0.500 m/s  vy=0.000 m/s");
  EXPECT_EQ(text_of(c, "0A2#10B6FDFF01000000"), "M5_2  theta=-1.50000 rad  command=1 (reset)");
  EXPECT_EQ(text_of(c, "7FF#00"), "[unknown id]");
  EXPECT_EQ(text_of(c, "131#F401"), "[wrong length 2, M6_1 has 8]");
  EXPECT_EQ(text_of(c, "20000044#0000000000000000"), "[error frame: controller,bus-off]");
  // What the data says, as linux/can/error.h lays it out: state, kind and place, counters.
  EXPECT_EQ(text_of(c, "20000204#0020000000008000"), "[error frame: controller,counters; tx-passive; TEC 128 REC 0]");
  EXPECT_EQ(text_of(c, "20000288#0000900A00000800"),
            "[error frame: protocol,bus-error,counters; bit1,tx in the data; TEC 8 REC 0]");
  EXPECT_EQ(text_of(c, "200002A8#0000801900000800"),
            "[error frame: protocol,no-ack,bus-error,counters; tx in the ACK slot; TEC 8 REC 0]");
  EXPECT_EQ(text_of(c, "131#R"), "[remote request for M6_1]");
  EXPECT_NE(text_of(c, "100#E8030000000000FF").find("setpoint_1=1000 counts/tick !out-of-range"), std::string::npos);
}

TEST(Describe, JsonCarriesValuesRawAndStatus) {
  const Codec c(load_dbc(test::shipped_dbc()));
  CanFrame f;
  ASSERT_TRUE(parse_compact("131#F401000000000000", f));
  EXPECT_EQ(describe_json(f, describe(c, f)),
            "{\"frame\":\"131#F401000000000000\",\"id\":\"0x131\",\"name\":\"M6_1\",\"status\":\"ok\",\"signals\":{"
            "\"vx\":{\"value\":0.5,\"unit\":\"m/s\",\"raw\":500,\"out_of_range\":false},"
            "\"vy\":{\"value\":0,\"unit\":\"m/s\",\"raw\":0,\"out_of_range\":false}}}");
  ASSERT_TRUE(parse_compact("131#F4", f));
  EXPECT_NE(describe_json(f, describe(c, f)).find("\"status\":\"wrong_length\""), std::string::npos);
}

TEST(Describe, JsonQuoteEscapes) { EXPECT_EQ(json_quote("a\"b\\c\n"), "\"a\\\"b\\\\c\\n\""); }

}  // namespace
}  // namespace canhil::frames
