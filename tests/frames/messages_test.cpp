#include "canhil/frames/messages.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "canhil/frames/candump.hpp"
#include "support/test_paths.hpp"

namespace canhil::frames {
namespace {

class Contract : public ::testing::Test {
 protected:
  std::shared_ptr<const MessageSet> set_ = MessageSet::load(test::shipped_dbc());
};

TEST_F(Contract, TypedEncodeGivesTheReadmeFrame) {
  EXPECT_EQ(format_compact(set_->m6_1.encode(M6_1{0.5, 0.0})), "131#F401000000000000");
}

TEST_F(Contract, TypedRoundTripsInSiUnits) {
  M4_1 pos{12.3456, -7.8901};
  M4_1 back;
  ASSERT_TRUE(set_->m4_1.decode(set_->m4_1.encode(pos), back).ok());
  EXPECT_NEAR(back.x, pos.x, 0.5e-4);
  EXPECT_NEAR(back.y, pos.y, 0.5e-4);

  M3 enc{-123456, -32, M3::kStatusStalled | M3::kStatusOverCurrent, 17};
  M3 enc_back;
  const CanFrame f = set_->m3[1].encode(enc);
  EXPECT_EQ(f.id, 0x112u);
  ASSERT_TRUE(set_->m3[1].decode(f, enc_back).ok());
  EXPECT_EQ(enc_back.encoder, enc.encoder);
  EXPECT_EQ(enc_back.delta, enc.delta);
  EXPECT_EQ(enc_back.status, enc.status);
  EXPECT_EQ(enc_back.seq, enc.seq);

  Tm tm{65535, 0x3FF, 2100};
  Tm tm_back;
  ASSERT_TRUE(set_->tm.decode(set_->tm.encode(tm), tm_back).ok());
  EXPECT_EQ(tm_back.ec_counter, 65535);
  EXPECT_EQ(tm_back.sync_bitmap, 0x3FFu);
  EXPECT_EQ(tm_back.sync_window_us, 2100);
}

TEST_F(Contract, TypedDecodeLeavesTheStructAloneOnWrongLength) {
  M6_1 v{9, 9};
  CanFrame f = set_->m6_1.encode(M6_1{1, 1});
  f.len = 4;
  EXPECT_EQ(set_->m6_1.decode(f, v).status, DecodeStatus::kWrongLength);
  EXPECT_EQ(v.vx, 9);
}

TEST_F(Contract, SaturatingEncodeReportsIt) {
  EncodeResult r;
  M1 sp{1200, -5, 0, 1, 0};
  const CanFrame f = set_->m1.encode(sp, &r);
  EXPECT_EQ(r.saturated, 1u);
  M1 back;
  set_->m1.decode(f, back);
  EXPECT_EQ(back.setpoint_1, 900);
}

TEST_F(Contract, KickByteHelpers) {
  M7 k;
  k.kick = M7::make_kick(true, 77);
  EXPECT_TRUE(k.low_kick());
  EXPECT_EQ(k.power(), M7::kMaxPower) << "power is capped to 50";
  k.kick = M7::make_kick(false, 20);
  EXPECT_FALSE(k.low_kick());
  EXPECT_EQ(k.power(), 20);
}

TEST_F(Contract, FttInformationComesFromTheDbc) {
  const Codec& c = set_->codec();
  EXPECT_EQ(set_->ftt(*c.find("TM")).kind, FttKind::kTrigger);
  EXPECT_EQ(set_->ftt(*c.find("TM")).period, std::chrono::milliseconds(10));
  const std::vector<std::pair<const char*, int>> order = {{"M1", 0},   {"M3_1", 1}, {"M3_2", 2}, {"M3_3", 3},
                                                          {"M4_1", 4}, {"M4_2", 5}, {"M6_1", 6}, {"M6_2", 7},
                                                          {"M8", 8},   {"M9", 9}};
  for (const auto& [name, index] : order) {
    EXPECT_EQ(set_->ftt(*c.find(name)).kind, FttKind::kSync) << name;
    EXPECT_EQ(set_->ftt(*c.find(name)).index, index) << name;
    EXPECT_EQ(set_->sync_message(index)->name(), name);
  }
  EXPECT_EQ(set_->ftt(*c.find("M3_2")).period, std::chrono::milliseconds(10));
  EXPECT_EQ(set_->ftt(*c.find("M4_1")).period, std::chrono::milliseconds(50));
  EXPECT_EQ(set_->ftt(*c.find("M6_2")).period, std::chrono::milliseconds(30));
  EXPECT_EQ(set_->ftt(*c.find("M7")).kind, FttKind::kAsync);
  EXPECT_EQ(set_->ftt(*c.find("M7")).min_gap, std::chrono::milliseconds(1000));
  EXPECT_EQ(set_->ftt(*c.find("M5_1")).min_gap, std::chrono::milliseconds(500));
  EXPECT_EQ(set_->sync_message(10), nullptr);
}

std::string shipped_text() {
  std::ifstream in(test::shipped_dbc());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void expect_rejected(const std::string& text, const std::string& says) {
  try {
    MessageSet::create(parse_dbc(text, "team.dbc"));
    FAIL() << "accepted";
  } catch (const DbcError& e) {
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "team.dbc");
  }
}

TEST(MessageSetChecks, DuplicateFttIndexIsRefused) {
  std::string t = shipped_text();
  t.replace(t.find("BA_ \"FttIndex\" BO_ 337 9;"), 25, "BA_ \"FttIndex\" BO_ 337 8;");
  expect_rejected(t, "has FttIndex 8 like M8");
}

TEST(MessageSetChecks, MissingSignalIsNamed) {
  std::string t = shipped_text();
  t.replace(t.find(" SG_ vy "), 8, " SG_ vz ");
  expect_rejected(t, "M6_1 has no signal vy");
}

TEST(MessageSetChecks, AsyncWithoutGapIsRefused) {
  std::string t = shipped_text();
  t.replace(t.find("BA_ \"GenMsgDelayTime\" BO_ 176 1000;"), 35, "");
  expect_rejected(t, "M7 is async but has no minimum gap");
}

TEST(MessageSetChecks, MissingMessageIsNamed) {
  std::string t = shipped_text();
  t.replace(t.find("BO_ 321 M8:"), 11, "BO_ 321 MX:");
  expect_rejected(t, "no message M8");
}

}  // namespace
}  // namespace canhil::frames
