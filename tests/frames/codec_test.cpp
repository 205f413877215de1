#include "canhil/frames/codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>

#include "canhil/frames/candump.hpp"
#include "canhil/frames/dbc.hpp"
#include "support/test_paths.hpp"

namespace canhil::frames {
namespace {

CanFrame frame_of(const std::string& compact) {
  CanFrame f;
  std::string error;
  EXPECT_TRUE(parse_compact(compact, f, &error)) << error;
  return f;
}

struct Row {
  const char* name;  // what the row shows
  const char* message;
  const char* frame;
  std::map<std::string, double> values;
};

// One named row per message of the contract at least: id, bytes, expected
// physical values. Bytes worked out by hand from message-set.md's layouts.
const std::vector<Row> kRows = {
    {"trigger message with all ten slots",
     "TM",
     "010#0100FF030000DC05",
     {{"ec_counter", 1}, {"sync_bitmap", 0x3FF}, {"sync_window_us", 1500}}},
    {"set points at both saturation limits",
     "M1",
     "100#84037CFC00000107",
     {{"setpoint_1", 900}, {"setpoint_2", -900}, {"setpoint_3", 0}, {"enable", 1}, {"seq", 7}}},
    {"encoder at -1, stalled",
     "M3_1",
     "111#FFFFFFFF2C0101C8",
     {{"encoder", -1}, {"delta", 300}, {"status", 1}, {"seq", 200}}},
    {"encoder positive, negative delta, over-current",
     "M3_2",
     "112#40E20100FBFF0200",
     {{"encoder", 123456}, {"delta", -5}, {"status", 2}, {"seq", 0}}},
    {"encoder at int32 max",
     "M3_3",
     "113#FFFFFF7F000000FF",
     {{"encoder", 2147483647}, {"delta", 0}, {"status", 0}, {"seq", 255}}},
    {"odometry position, 0.1 mm units", "M4_1", "121#983A00001CA8FFFF", {{"x", 1.5}, {"y", -2.25}}},
    {"odometry heading at +pi", "M4_2", "122#2FCB040001020000", {{"theta", 3.14159}, {"seq", 513}}},
    {"the README's example", "M6_1", "131#F401000000000000", {{"vx", 0.5}, {"vy", 0}}},
    {"backwards and sideways", "M6_1", "131#18FCD00700000000", {{"vx", -1}, {"vy", 2}}},
    {"turning right with small adjustment",
     "M6_2",
     "132#30F8010900000000",
     {{"va", -2}, {"small_adjustment", 1}, {"seq", 9}}},
    {"compass east", "M8", "141#28239CFF00000000", {{"heading", 90}, {"raw", -100}}},
    {"ball engaged, capacitor charged",
     "M9",
     "151#01000D0732000000",
     {{"ball_engaged", 1}, {"just_kicked", 0}, {"kicker_voltage", 180.5}, {"grabber", 50}}},
    {"set odometry position", "M5_1", "0A1#78ECFFFF409C0000", {{"x", -0.5}, {"y", 4}}},
    {"reset odometry", "M5_2", "0A2#10B6FDFF01000000", {{"theta", -1.5}, {"command", 1}}},
    {"low kick at full power",
     "M7",
     "0B0#B2640A0500000000",
     {{"kick", 0xB2}, {"grabber_mode", 100}, {"eng_lvl_high", 10}, {"eng_lvl_low", 5}}},
    {"battery rails",
     "M2",
     "200#F401D20492090000",
     {{"v_logic", 5.0}, {"v_power12", 12.34}, {"v_power24", 24.5}, {"v_kicker", 0}}},
    {"all nodes alive", "M10", "210#3FE8030200000000", {{"alive", 0x3F}, {"errors", 1000}, {"node_state", 2}}},
};

class ShippedCodec : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { codec_ = new Codec(load_dbc(test::shipped_dbc())); }
  static void TearDownTestSuite() { delete codec_; }
  static Codec* codec_;
};
Codec* ShippedCodec::codec_ = nullptr;

TEST_F(ShippedCodec, EveryMessageHasARow) {
  for (const MessageCodec& m : codec_->messages()) {
    const bool found = std::any_of(kRows.begin(), kRows.end(), [&](const Row& r) { return r.message == m.name(); });
    EXPECT_TRUE(found) << "no table row for " << m.name();
  }
}

TEST_F(ShippedCodec, DecodesTableRows) {
  for (const Row& row : kRows) {
    SCOPED_TRACE(row.name);
    const CanFrame f = frame_of(row.frame);
    const MessageCodec* m = codec_->find(f.id);
    ASSERT_NE(m, nullptr) << row.frame;
    EXPECT_EQ(m->name(), row.message);
    std::array<double, kMaxSignals> out{};
    const DecodeResult r = m->decode(f, out);
    ASSERT_EQ(r.status, DecodeStatus::kOk);
    EXPECT_EQ(r.out_of_range, 0u);
    ASSERT_EQ(row.values.size(), m->signal_count());
    for (const auto& [signal, expected] : row.values) {
      const auto i = m->index_of(signal);
      ASSERT_TRUE(i) << signal;
      EXPECT_NEAR(out[*i], expected, 1e-9 + std::fabs(m->def().signals[*i].factor) * 1e-6) << signal;
    }
  }
}

TEST_F(ShippedCodec, EncodesTableRows) {
  for (const Row& row : kRows) {
    SCOPED_TRACE(row.name);
    const MessageCodec* m = codec_->find(row.message);
    ASSERT_NE(m, nullptr);
    std::array<double, kMaxSignals> in{};
    for (const auto& [signal, value] : row.values) in[*m->index_of(signal)] = value;
    CanFrame f;
    const EncodeResult r = m->encode(std::span<const double>(in.data(), m->signal_count()), f);
    EXPECT_TRUE(r.ok());
    EXPECT_EQ(format_compact(f), row.frame);
  }
}

// Every signal over its whole range: exhaustive up to 16 bits, limits plus a
// seeded sample beyond. Encode(raw * factor + offset) must give back the raw.
TEST_F(ShippedCodec, RoundTripsEverySignalOverItsRange) {
  std::mt19937_64 rng(20261121);
  for (const MessageCodec& m : codec_->messages()) {
    for (std::size_t i = 0; i < m.signal_count(); ++i) {
      const SignalLayout& l = m.layout(i);
      SCOPED_TRACE(std::string(m.name()) + "." + m.def().signals[i].name);
      std::vector<std::int64_t> raws;
      const std::int64_t span = l.raw_max - l.raw_min;
      if (span <= 65535) {
        for (std::int64_t v = l.raw_min; v <= l.raw_max; ++v) raws.push_back(v);
      } else {
        raws = {l.raw_min, l.raw_min + 1, -1, 0, 1, l.raw_max - 1, l.raw_max};
        std::uniform_int_distribution<std::int64_t> dist(l.raw_min, l.raw_max);
        for (int k = 0; k < 20000; ++k) raws.push_back(dist(rng));
      }
      std::array<double, kMaxSignals> in{};
      std::array<double, kMaxSignals> out{};
      for (const std::int64_t raw : raws) {
        if (raw < l.raw_min || raw > l.raw_max) continue;
        in[i] = static_cast<double>(raw) * l.factor + l.offset;
        CanFrame f;
        ASSERT_TRUE(m.encode(std::span<const double>(in.data(), m.signal_count()), f).ok()) << raw;
        const std::uint64_t bits = m.raw_bits(f, i);
        ASSERT_EQ(bits, static_cast<std::uint64_t>(raw) & l.mask) << raw;
        ASSERT_EQ(m.decode(f, out).status, DecodeStatus::kOk);
        ASSERT_NEAR(out[i], in[i], std::fabs(l.factor) * 1e-6) << raw;
      }
    }
  }
}

TEST_F(ShippedCodec, SaturatesOutOfRangeAndFlagsIt) {
  const MessageCodec* m1 = codec_->find("M1");
  std::array<double, kMaxSignals> in{};
  in[0] = 1000;   // above +900
  in[1] = -1e12;  // far below -900
  in[2] = std::nan("");
  CanFrame f;
  const EncodeResult r = m1->encode(std::span<const double>(in.data(), m1->signal_count()), f);
  EXPECT_EQ(r.saturated, 0b111u);
  std::array<double, kMaxSignals> out{};
  ASSERT_EQ(m1->decode(f, out).status, DecodeStatus::kOk);
  EXPECT_EQ(out[0], 900);
  EXPECT_EQ(out[1], -900);
  EXPECT_EQ(out[2], 0);  // NaN encodes the initial value
}

TEST_F(ShippedCodec, FlagsDecodedValuesOutsideTheDeclaredRange) {
  const CanFrame f = frame_of("100#E8030000000000FF");  // setpoint_1 = 1000 > 900
  std::array<double, kMaxSignals> out{};
  const DecodeResult r = codec_->find("M1")->decode(f, out);
  EXPECT_EQ(r.status, DecodeStatus::kOk);
  EXPECT_EQ(r.out_of_range, 1u);
  EXPECT_EQ(out[0], 1000);
  EXPECT_FALSE(r.ok());
}

TEST_F(ShippedCodec, RefusesWrongLengthAndNonDataFrames) {
  std::array<double, kMaxSignals> out{};
  out.fill(42);
  const MessageCodec* m = codec_->find("M6_1");
  EXPECT_EQ(m->decode(frame_of("131#F401"), out).status, DecodeStatus::kWrongLength);
  EXPECT_EQ(m->decode(frame_of("131#R"), out).status, DecodeStatus::kNotData);
  EXPECT_EQ(out[0], 42) << "nothing may be decoded from a frame that does not fit";
  EXPECT_EQ(codec_->decode(frame_of("7FF#00"), out).status, DecodeStatus::kUnknownId);
  EXPECT_EQ(codec_->decode(frame_of("20000004#0000000000000000"), out).status, DecodeStatus::kNotData);
}

TEST_F(ShippedCodec, FindsByIdInConstantTimeTable) {
  EXPECT_EQ(codec_->find(0x131)->name(), "M6_1");
  EXPECT_EQ(codec_->find(0x010)->name(), "TM");
  EXPECT_EQ(codec_->find(0x7FF), nullptr);
  EXPECT_EQ(codec_->find(0x131, true), nullptr) << "an extended 0x131 is another message";
  EXPECT_EQ(codec_->find(0x12345678), nullptr);
}

// is_message, the one "is this frame that message" rule of every receiver:
// a data frame with the message's id, standard or extended as declared; any
// length (a wrong one is the message, counted as bad when decoded).
struct IsRow {
  const char* name;
  const char* message;
  const char* frame;
  bool is;
};

TEST_F(ShippedCodec, IsMessageIsADataFrameWithTheIdOfTheDeclaredKind) {
  const IsRow rows[] = {
      {"the trigger message", "TM", "010#0100FF030000DC05", true},
      {"of the wrong length: still the message", "TM", "010#01", true},
      {"of no bytes", "M6_1", "131#", true},
      {"a remote frame with its id", "TM", "010#R", false},
      {"an extended frame with the same number", "TM", "00000010#0100FF030000DC05", false},
      {"another message's id", "TM", "131#F401000000000000", false},
      {"an error frame", "TM", "20000004#0000000000000000", false},
  };
  for (const IsRow& r : rows) {
    SCOPED_TRACE(r.name);
    EXPECT_EQ(is_message(frame_of(r.frame), *codec_->find(r.message)), r.is) << r.frame;
  }
}

// A database with Motorola, float and offset signals, checked against bytes
// worked out by hand (Vector's sawtooth bit numbering).
constexpr const char* kMixedDbc = R"(VERSION ""
BU_: A B
BO_ 1024 MOTO: 8 A
 SG_ be12 : 7|12@0+ (1,0) [0|4095] "" B
 SG_ be_signed : 11|8@0- (0.5,-10) [0|0] "" B
 SG_ le_float : 32|32@1- (1,0) [0|0] "" B
BO_ 2147484672 EXTD: 8 A
 SG_ dbl : 7|64@0- (1,0) [0|0] "" B
SIG_VALTYPE_ 1024 le_float : 1;
SIG_VALTYPE_ 2147484672 dbl : 2;
)";

TEST(MixedCodec, MotorolaFloatAndOffsetMatchHandWorkedBytes) {
  const Codec codec(parse_dbc(kMixedDbc, "mixed.dbc"));
  const MessageCodec* m = codec.find("MOTO");
  ASSERT_NE(m, nullptr);
  std::array<double, kMaxSignals> in{};
  in[0] = 0xABC;
  in[1] = -12.5;  // raw (-12.5 + 10) / 0.5 = -5 = 0xFB as 8-bit
  in[2] = 1.5;    // float 0x3FC00000
  CanFrame f;
  ASSERT_TRUE(m->encode(std::span<const double>(in.data(), 3), f).ok());
  // be12: byte0 = AB, byte1 high nibble = C; be_signed MSB at bit 11 (byte1 bit3):
  // byte1 low nibble = F, byte2 high nibble = B.
  EXPECT_EQ(format_compact(f), "400#ABCFB0000000C03F");
  std::array<double, kMaxSignals> out{};
  ASSERT_EQ(m->decode(f, out).status, DecodeStatus::kOk);
  EXPECT_EQ(out[0], 0xABC);
  EXPECT_EQ(out[1], -12.5);
  EXPECT_EQ(out[2], 1.5);

  const MessageCodec* e = codec.find(0x400, true);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->name(), "EXTD");
  in[0] = -2.0;  // 0xC000000000000000, big endian
  ASSERT_TRUE(e->encode(std::span<const double>(in.data(), 1), f).ok());
  EXPECT_EQ(format_compact(f), "00000400#C000000000000000");
  ASSERT_EQ(e->decode(f, out).status, DecodeStatus::kOk);
  EXPECT_EQ(out[0], -2.0);
  EXPECT_TRUE(is_message(f, *e)) << "an extended message is its extended frame";
  f.extended = false;
  EXPECT_FALSE(is_message(f, *e)) << "not the standard frame of the same number";
}

// Integer messages: Intel and Motorola, signed and unsigned, a declared range
// narrower than the bits, 53 bits, start values (one beyond its range).
constexpr const char* kIntegerDbc = R"(VERSION ""
BU_: A B
BO_ 512 INTS: 8 A
 SG_ le_u5 : 0|5@1+ (1,0) [0|20] "" B
 SG_ le_s11 : 5|11@1- (1,0) [-100|100] "" B
 SG_ be_u12 : 23|12@0+ (1,0) [0|0] "" B
 SG_ be_s9 : 27|9@0- (1,0) [0|0] "" B
 SG_ le_s24 : 40|24@1- (1,0) [0|0] "" B
BO_ 513 WIDE: 8 A
 SG_ u53 : 0|53@1+ (1,0) [0|0] "" B
 SG_ s11 : 53|11@1- (1,0) [0|0] "" B
BO_ 514 SCALED: 8 A
 SG_ a : 0|16@1- (1,0) [0|0] "" B
 SG_ b : 16|16@1- (0.01,0) [0|0] "" B
BA_DEF_ SG_  "GenSigStartValue" INT -2147483648 2147483647;
BA_DEF_DEF_  "GenSigStartValue" 0;
BA_ "GenSigStartValue" SG_ 512 le_s11 -7;
BA_ "GenSigStartValue" SG_ 512 le_u5 30;
)";

TEST(IntegerCodec, GivesWhatTheGenericPathGivesForEveryFrameAndValue) {
  const Codec codec(parse_dbc(kIntegerDbc, "ints.dbc"));
  const Codec shipped(load_dbc(test::shipped_dbc()));
  EXPECT_FALSE(codec.find("SCALED")->plain_integers()) << "a factor other than 1";
  std::vector<const MessageCodec*> messages = {codec.find("INTS"), codec.find("WIDE")};
  for (const char* name : {"TM", "M1", "M3_1"}) messages.push_back(shipped.find(name));
  std::mt19937_64 rng(7);
  for (const MessageCodec* m : messages) {
    ASSERT_TRUE(m->plain_integers()) << m->name();
    const std::size_t n = m->signal_count();
    ASSERT_EQ(m->initial_integers().size(), n);
    for (int trial = 0; trial < 20'000; ++trial) {
      // Decoding: random bytes, now and then a wrong length or a remote frame.
      CanFrame f;
      f.id = m->id();
      f.extended = m->def().extended;
      f.len = static_cast<std::uint8_t>(trial % 97 == 0 ? 3 : m->def().length);
      if (trial % 89 == 0) f.kind = FrameKind::kRemote;
      const std::uint64_t bytes = rng();
      std::memcpy(f.data.data(), &bytes, f.len);
      std::array<double, kMaxSignals> as_doubles{};
      std::array<std::int64_t, kMaxSignals> as_integers{};
      const DecodeResult generic = m->decode(f, as_doubles);
      const DecodeResult integers = m->decode_integers(f, as_integers);
      ASSERT_EQ(integers.status, generic.status) << m->name() << " " << format_compact(f);
      ASSERT_EQ(integers.out_of_range, generic.out_of_range) << m->name() << " " << format_compact(f);
      if (generic.status == DecodeStatus::kOk) {
        for (std::size_t i = 0; i < n; ++i) {
          ASSERT_EQ(static_cast<double>(as_integers[i]), as_doubles[i]) << m->name() << " signal " << i;
        }
      }
      // Encoding: values around and beyond each signal's range, or its start value.
      std::array<std::int64_t, kMaxSignals> values{};
      std::array<double, kMaxSignals> doubles{};
      for (std::size_t i = 0; i < n; ++i) {
        const SignalLayout& l = m->layout(i);
        switch (rng() % 4) {
          case 0:
            values[i] = m->initial_integers()[i];
            break;
          case 1:
            values[i] = (rng() % 2 != 0 ? l.raw_min : l.raw_max) + static_cast<std::int64_t>(rng() % 3) - 1;
            break;
          case 2:
            values[i] = static_cast<std::int64_t>(rng() % (std::uint64_t{1} << 41)) - (std::int64_t{1} << 40);
            break;
          default:
            values[i] =
                l.raw_min + static_cast<std::int64_t>(rng() % static_cast<std::uint64_t>(l.raw_max - l.raw_min + 1));
        }
        doubles[i] = static_cast<double>(values[i]);
        ASSERT_EQ(static_cast<double>(m->initial_integers()[i]), m->initial_values()[i]) << m->name() << " " << i;
      }
      CanFrame by_doubles;
      CanFrame by_integers;
      const EncodeResult a = m->encode(std::span<const double>(doubles.data(), n), by_doubles);
      const EncodeResult b = m->encode_integers(std::span<const std::int64_t>(values.data(), n), by_integers);
      ASSERT_EQ(b.saturated, a.saturated) << m->name();
      ASSERT_EQ(format_compact(by_integers), format_compact(by_doubles)) << m->name();
    }
  }
}

// A database made in code skips the parser's checks: the codec itself must
// stay defined for any numbers (the fuzzer found a huge offset turning the raw
// range's bound into an out-of-range cast).
TEST(HostileNumbers, CodecStaysDefinedWhenTheRangeMissesTheBits) {
  Database db;
  MessageDef m;
  m.name = "H";
  m.id = 1;
  m.length = 8;
  for (const double offset : {3.3e68, -3.3e68, 1e300}) {
    SignalDef s;
    s.name = "s" + std::to_string(m.signals.size());
    s.start_bit = static_cast<std::uint16_t>(16 * m.signals.size());
    s.length = 16;
    s.value_type = ValueType::kSigned;
    s.factor = 1e-300;
    s.offset = offset;
    s.minimum = -32768;
    s.maximum = 32767;
    s.attributes["GenSigStartValue"] = 1e300;
    m.signals.push_back(s);
  }
  db.messages.push_back(m);
  const Codec codec(std::move(db));
  const MessageCodec& c = codec.messages().front();
  for (std::size_t i = 0; i < c.signal_count(); ++i) EXPECT_LE(c.layout(i).raw_min, c.layout(i).raw_max);
  std::array<double, kMaxSignals> in{};
  CanFrame f;
  const EncodeResult e = c.encode(std::span<const double>(in.data(), 3), f);
  EXPECT_EQ(e.saturated, 0b111u);  // 0 is nowhere near any of these ranges
  std::array<double, kMaxSignals> out{};
  const DecodeResult d = c.decode(f, out);
  EXPECT_EQ(d.status, DecodeStatus::kOk);
}

TEST(HostileNumbers, TheFuzzersFindingIsRefusedWithItsLine) {
  const std::string path = canhil::test::source_dir() + "/fuzz/corpus/dbc/regression-codec-raw-range-ub.dbc";
  try {
    load_dbc(path);
    FAIL() << "accepted";
  } catch (const DbcError& e) {
    EXPECT_EQ(e.line(), 26) << e.what();
    EXPECT_NE(std::string(e.what()).find("signal encoder of M3_3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace canhil::frames
