#include "canhil/frames/candump.hpp"

#include <gtest/gtest.h>

namespace canhil::frames {
namespace {

struct CompactRow {
  const char* text;
  CanFrame frame;
  const char* canonical;  // what format_compact writes back
};

CanFrame data(std::uint32_t id, bool ext, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f = make_data_frame(id, bytes);
  f.extended = ext;
  return f;
}
CanFrame remote(std::uint32_t id, std::uint8_t len) {
  CanFrame f;
  f.id = id;
  f.kind = FrameKind::kRemote;
  f.len = len;
  return f;
}
CanFrame error_frame(std::uint32_t classes) {
  CanFrame f;
  f.kind = FrameKind::kError;
  f.id = classes;
  f.len = 8;
  return f;
}

TEST(Compact, ParsesAndWritesCanUtilsRows) {
  CanFrame dlc_frame = data(0x123, false, {1, 2, 3, 4, 5, 6, 7, 8});
  dlc_frame.len8_dlc = 0xC;
  const CompactRow rows[] = {
      {"131#F401000000000000", data(0x131, false, {0xF4, 0x01, 0, 0, 0, 0, 0, 0}), "131#F401000000000000"},
      {"5A1#11.2233.44556677.88", data(0x5A1, false, {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88}),
       "5A1#1122334455667788"},
      {"123#", data(0x123, false, {}), "123#"},
      {"1F334455#1122", data(0x1F334455, true, {0x11, 0x22}), "1F334455#1122"},
      {"00000123#ab", data(0x123, true, {0xAB}), "00000123#AB"},
      {"123#R", remote(0x123, 0), "123#R"},
      {"123#R3", remote(0x123, 3), "123#R3"},
      {"20000004#0000000000000000", error_frame(0x4), "20000004#0000000000000000"},
      {"123#0102030405060708_C", dlc_frame, "123#0102030405060708_C"},
  };
  for (const CompactRow& row : rows) {
    CanFrame f;
    std::string error;
    ASSERT_TRUE(parse_compact(row.text, f, &error)) << row.text << ": " << error;
    EXPECT_EQ(f, row.frame) << row.text;
    EXPECT_EQ(format_compact(f), row.canonical);
  }
}

TEST(Compact, RejectsMalformedTextWithAReason) {
  const std::pair<const char*, const char*> bad[] = {
      {"131F401", "no '#'"},
      {"13#00", "3 (standard) or 8 (extended)"},
      {"800#00", "above 7FF"},
      {"G31#00", "not hexadecimal"},
      {"131#F40", "odd number"},
      {"131#ZZ", "not hexadecimal"},
      {"131#001122334455667788", "more than 8"},
      {"131##1F4", "CAN FD"},
      {"131#R9", "one digit 0..8"},
      {"131#0011_C", "needs 8 data bytes"},
      {"20000004#00", "8 data bytes"},
  };
  for (const auto& [text, says] : bad) {
    CanFrame f;
    std::string error;
    EXPECT_FALSE(parse_compact(text, f, &error)) << text;
    EXPECT_NE(error.find(says), std::string::npos) << text << " -> " << error;
  }
}

TEST(Log, ReadsAndWritesCandumpLogLines) {
  LogEntry e;
  std::string error;
  ASSERT_TRUE(parse_log_line("(1700000000.000100) vcan0 131#F401000000000000\n", e, &error)) << error;
  EXPECT_EQ(e.time, std::chrono::seconds(1700000000) + std::chrono::microseconds(100));
  EXPECT_EQ(e.iface, "vcan0");
  EXPECT_EQ(e.frame, data(0x131, false, {0xF4, 0x01, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(format_log_line(e.time, e.iface, e.frame), "(1700000000.000100) vcan0 131#F401000000000000");

  ASSERT_TRUE(parse_log_line("(0000000001.500000) can1 20000040#0000000000000000 R", e, &error)) << error;
  EXPECT_EQ(e.frame.kind, FrameKind::kError);
  EXPECT_EQ(e.frame.id, 0x40u);
  EXPECT_EQ(format_log_line(e.time, "can1", e.frame), "(0000000001.500000) can1 20000040#0000000000000000");
}

TEST(Log, RejectsMalformedLines) {
  const char* bad[] = {"1700000000.000100 vcan0 131#00",
                       "(1700000000.0001) vcan0 131#00",
                       "(1700000000.000100) vcan0",
                       "(17000x0000.000100) vcan0 131#00",
                       "(1700000000.000100) vcan0 131#00 extra words",
                       "(1700000000.000100 vcan0 131#00",
                       "(17000000000.000100) vcan0 131#00" /* found by fuzz.decode: ns overflow */};
  for (const char* line : bad) {
    LogEntry e;
    std::string error;
    EXPECT_FALSE(parse_log_line(line, e, &error)) << line;
    EXPECT_FALSE(error.empty());
  }
}

TEST(Compact, FormatsWithoutAllocatingIntoAFixedBuffer) {
  char buf[kCompactMaxChars];
  CanFrame f = data(0x1FFFFFFF, true, {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  f.len8_dlc = 15;
  EXPECT_EQ(format_compact(f, buf), kCompactMaxChars - 1);
  EXPECT_STREQ(buf, "1FFFFFFF#FFFFFFFFFFFFFFFF_F");
}

}  // namespace
}  // namespace canhil::frames
