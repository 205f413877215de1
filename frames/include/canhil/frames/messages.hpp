// canhil/frames/messages.hpp — the contract's messages as typed structs.
//
// Field names are the signal names of shared/design/message-set.md; values are
// in the DBC's physical units, which are SI (m, m/s, rad, rad/s, V) except
// where the contract says otherwise (counts, counts per 5 ms tick, deg for the
// compass heading, us for the trigger window). Bindings are made by signal
// name when a MessageSet is built, so a team's DBC may move, resize or
// rescale signals without touching code; a missing signal is a DbcError.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>
#include <tuple>
#include <type_traits>

#include "canhil/frames/codec.hpp"

namespace canhil::frames {

struct Tm {  // 0x010 FTT trigger message, every EC
  std::uint16_t ec_counter = 0;
  std::uint32_t sync_bitmap = 0;  ///< bit i: synchronous message with FTT index i is due in this EC
  std::uint16_t sync_window_us = 0;
};
struct M1 {                     // 0x100 Pic_base -> Motor1..3: wheel set points
  std::int16_t setpoint_1 = 0;  ///< encoder counts per 5 ms motor tick, ±900
  std::int16_t setpoint_2 = 0;
  std::int16_t setpoint_3 = 0;
  std::uint8_t enable = 0;  ///< 0 = brake
  std::uint8_t seq = 0;
};
struct M3 {                  // 0x111..0x113 Motor n -> Pic_odom: encoder
  std::int32_t encoder = 0;  ///< absolute count, wraps
  std::int16_t delta = 0;    ///< counts since the previous M3
  std::uint8_t status = 0;   ///< kStatusStalled | kStatusOverCurrent
  std::uint8_t seq = 0;
  static constexpr std::uint8_t kStatusStalled = 0x01;
  static constexpr std::uint8_t kStatusOverCurrent = 0x02;
};
struct M4_1 {    // 0x121 Pic_odom -> Laptop: position
  double x = 0;  ///< m
  double y = 0;  ///< m
};
struct M4_2 {        // 0x122 Pic_odom -> Laptop: heading
  double theta = 0;  ///< rad, (-pi, pi]
  std::uint16_t seq = 0;
};
struct M5_1 {    // 0x0A1 Laptop -> Pic_odom: set position
  double x = 0;  ///< m
  double y = 0;  ///< m
};
struct M5_2 {                // 0x0A2 Laptop -> Pic_odom: set heading / reset
  double theta = 0;          ///< rad
  std::uint8_t command = 0;  ///< kSetPose or kReset
  static constexpr std::uint8_t kSetPose = 0;
  static constexpr std::uint8_t kReset = 1;
};
struct M6_1 {     // 0x131 Laptop -> Pic_base: linear velocity, robot frame (y forward)
  double vx = 0;  ///< m/s
  double vy = 0;  ///< m/s
};
struct M6_2 {     // 0x132 Laptop -> Pic_base: angular velocity
  double va = 0;  ///< rad/s
  std::uint8_t small_adjustment = 0;
  std::uint8_t seq = 0;
};
struct M7 {                       // 0x0B0 Laptop -> Pic_base: kick and grabber
  std::uint8_t kick = 0;          ///< bit7 = 1 low (direct) kick, 0 high (lob); bits 0-6 power (capped to 50)
  std::uint8_t grabber_mode = 0;  ///< 0..100
  std::uint8_t eng_lvl_high = 0;
  std::uint8_t eng_lvl_low = 0;

  static constexpr std::uint8_t kLowKickBit = 0x80;
  static constexpr std::uint8_t kMaxPower = 50;
  bool low_kick() const noexcept { return (kick & kLowKickBit) != 0; }
  /// Requested power, capped to kMaxPower as the firmware does.
  std::uint8_t power() const noexcept {
    const auto p = static_cast<std::uint8_t>(kick & 0x7F);
    return p > kMaxPower ? kMaxPower : p;
  }
  static constexpr std::uint8_t make_kick(bool low, std::uint8_t power) noexcept {
    return static_cast<std::uint8_t>((low ? kLowKickBit : 0) | (power & 0x7F));
  }
};
struct M2 {            // 0x200 Pic_base -> Laptop: battery
  double v_logic = 0;  ///< V
  double v_power12 = 0;
  double v_power24 = 0;
  double v_kicker = 0;
};
struct M8 {            // 0x141 Compass -> Laptop
  double heading = 0;  ///< deg from magnetic north, [0, 360)
  std::int16_t raw = 0;
};
struct M9 {  // 0x151 Pic_base -> Laptop: kick system status
  std::uint8_t ball_engaged = 0;
  std::uint8_t just_kicked = 0;
  double kicker_voltage = 0;  ///< V
  std::uint8_t grabber = 0;
};
struct M10 {               // 0x210 System monitor -> Laptop: node health
  std::uint8_t alive = 0;  ///< bit0 Pic_base, bit1..3 Motor1..3, bit4 Pic_odom, bit5 Compass
  std::uint16_t errors = 0;
  std::uint8_t node_state = 0;
};

/// A field of a typed message: the signal it binds to and the member.
template <class Struct, class Member>
struct FieldRef {
  std::string_view signal;
  Member Struct::*member;
};
template <class Struct, class Member>
constexpr FieldRef<Struct, Member> field(std::string_view signal, Member Struct::*member) {
  return {signal, member};
}

/// Specialised for each typed message: kName (the DBC message name; empty for
/// M3, which serves M3_1..M3_3) and kFields.
template <class T>
struct MessageTraits;

#define CANHIL_MESSAGE_TRAITS(Type, Name, ...)                    \
  template <>                                                     \
  struct MessageTraits<Type> {                                    \
    static constexpr std::string_view kName = Name;               \
    static constexpr auto kFields = std::make_tuple(__VA_ARGS__); \
  }

CANHIL_MESSAGE_TRAITS(Tm, "TM", field("ec_counter", &Tm::ec_counter), field("sync_bitmap", &Tm::sync_bitmap),
                      field("sync_window_us", &Tm::sync_window_us));
CANHIL_MESSAGE_TRAITS(M1, "M1", field("setpoint_1", &M1::setpoint_1), field("setpoint_2", &M1::setpoint_2),
                      field("setpoint_3", &M1::setpoint_3), field("enable", &M1::enable), field("seq", &M1::seq));
CANHIL_MESSAGE_TRAITS(M3, "", field("encoder", &M3::encoder), field("delta", &M3::delta), field("status", &M3::status),
                      field("seq", &M3::seq));
CANHIL_MESSAGE_TRAITS(M4_1, "M4_1", field("x", &M4_1::x), field("y", &M4_1::y));
CANHIL_MESSAGE_TRAITS(M4_2, "M4_2", field("theta", &M4_2::theta), field("seq", &M4_2::seq));
CANHIL_MESSAGE_TRAITS(M5_1, "M5_1", field("x", &M5_1::x), field("y", &M5_1::y));
CANHIL_MESSAGE_TRAITS(M5_2, "M5_2", field("theta", &M5_2::theta), field("command", &M5_2::command));
CANHIL_MESSAGE_TRAITS(M6_1, "M6_1", field("vx", &M6_1::vx), field("vy", &M6_1::vy));
CANHIL_MESSAGE_TRAITS(M6_2, "M6_2", field("va", &M6_2::va), field("small_adjustment", &M6_2::small_adjustment),
                      field("seq", &M6_2::seq));
CANHIL_MESSAGE_TRAITS(M7, "M7", field("kick", &M7::kick), field("grabber_mode", &M7::grabber_mode),
                      field("eng_lvl_high", &M7::eng_lvl_high), field("eng_lvl_low", &M7::eng_lvl_low));
CANHIL_MESSAGE_TRAITS(M2, "M2", field("v_logic", &M2::v_logic), field("v_power12", &M2::v_power12),
                      field("v_power24", &M2::v_power24), field("v_kicker", &M2::v_kicker));
CANHIL_MESSAGE_TRAITS(M8, "M8", field("heading", &M8::heading), field("raw", &M8::raw));
CANHIL_MESSAGE_TRAITS(M9, "M9", field("ball_engaged", &M9::ball_engaged), field("just_kicked", &M9::just_kicked),
                      field("kicker_voltage", &M9::kicker_voltage), field("grabber", &M9::grabber));
CANHIL_MESSAGE_TRAITS(M10, "M10", field("alive", &M10::alive), field("errors", &M10::errors),
                      field("node_state", &M10::node_state));
#undef CANHIL_MESSAGE_TRAITS

/// A typed view of one message of a Codec. Cheap to copy; valid while the Codec lives.
template <class T>
class TypedCodec {
  // Members whose every value is exact in a double and back: integers of up to 32 bits.
  template <class Field>
  struct SmallInteger;
  template <class Struct, class Member>
  struct SmallInteger<FieldRef<Struct, Member>>
      : std::bool_constant<std::is_integral_v<Member> && sizeof(Member) <= sizeof(std::uint32_t)> {};
  template <class Fields>
  struct AllSmallIntegers;
  template <class... Fields>
  struct AllSmallIntegers<std::tuple<Fields...>> : std::bool_constant<(SmallInteger<Fields>::value && ...)> {};

 public:
  static constexpr std::size_t kFieldCount = std::tuple_size_v<decltype(MessageTraits<T>::kFields)>;
  /// Every member an integer of up to 32 bits: on a MessageCodec::plain_integers()
  /// message the values then go as integers, never through doubles (the same frames and values).
  static constexpr bool kIntegerFields = AllSmallIntegers<std::remove_cv_t<decltype(MessageTraits<T>::kFields)>>::value;

  TypedCodec() = default;
  /// Binds by signal name; throws DbcError naming the message and the missing signal.
  explicit TypedCodec(const Codec& codec, std::string_view message_name = MessageTraits<T>::kName) {
    message_ = codec.find(message_name);
    if (message_ == nullptr) {
      throw DbcError(codec.database().file, 0,
                     "the message set has no message " + std::string(message_name) +
                         "; canhil needs it (see docs/message-set.md)");
    }
    std::size_t k = 0;
    std::apply([&](const auto&... f) { ((index_[k++] = bind(codec.database().file, f.signal)), ...); },
               MessageTraits<T>::kFields);
    integers_ = kIntegerFields && message_->plain_integers();
  }

  const MessageCodec& message() const noexcept { return *message_; }

  /// Encodes `value`; signals without a field keep their initial value.
  CanFrame encode(const T& value, EncodeResult* result = nullptr) const noexcept {
    if (integers_) return encode_integers(value, result);
    std::array<double, kMaxSignals> values;  // only the first signal_count() are used; no zero fill
    const auto init = message_->initial_values();
    std::copy(init.begin(), init.end(), values.begin());
    std::size_t k = 0;
    std::apply([&](const auto&... f) { ((values[index_[k++]] = static_cast<double>(value.*(f.member))), ...); },
               MessageTraits<T>::kFields);
    CanFrame frame;
    const EncodeResult r = message_->encode(std::span<const double>(values.data(), message_->signal_count()), frame);
    if (result != nullptr) *result = r;
    return frame;
  }

  /// Decodes `frame` into `out`; `out` is untouched unless the status is kOk.
  DecodeResult decode(const CanFrame& frame, T& out) const noexcept {
    if (integers_) return decode_integers(frame, out);
    std::array<double, kMaxSignals> values;  // decode fills the first signal_count()
    const DecodeResult r = message_->decode(frame, values);
    if (r.status != DecodeStatus::kOk) return r;
    std::size_t k = 0;
    std::apply([&](const auto&... f) { ((assign(out.*(f.member), values[index_[k++]])), ...); },
               MessageTraits<T>::kFields);
    return r;
  }

 private:
  std::uint8_t bind(const std::string& file, std::string_view signal) const {
    const auto i = message_->index_of(signal);
    if (!i) {
      throw DbcError(file, message_->def().line,
                     "message " + std::string(message_->name()) + " has no signal " + std::string(signal) +
                         "; canhil needs it (see docs/message-set.md)");
    }
    return static_cast<std::uint8_t>(*i);
  }
  CanFrame encode_integers(const T& value, EncodeResult* result) const noexcept {
    std::array<std::int64_t, kMaxSignals> values;  // as encode()
    const auto init = message_->initial_integers();
    std::copy(init.begin(), init.end(), values.begin());
    std::size_t k = 0;
    std::apply([&](const auto&... f) { ((values[index_[k++]] = static_cast<std::int64_t>(value.*(f.member))), ...); },
               MessageTraits<T>::kFields);
    CanFrame frame;
    const EncodeResult r =
        message_->encode_integers(std::span<const std::int64_t>(values.data(), message_->signal_count()), frame);
    if (result != nullptr) *result = r;
    return frame;
  }
  DecodeResult decode_integers(const CanFrame& frame, T& out) const noexcept {
    std::array<std::int64_t, kMaxSignals> values;  // as decode()
    const DecodeResult r = message_->decode_integers(frame, values);
    if (r.status != DecodeStatus::kOk) return r;
    std::size_t k = 0;
    std::apply(
        [&](const auto&... f) {
          ((out.*(f.member) = static_cast<std::remove_cvref_t<decltype(out.*(f.member))>>(values[index_[k++]])), ...);
        },
        MessageTraits<T>::kFields);
    return r;
  }
  template <class M>
  static void assign(M& member, double v) noexcept {
    if constexpr (std::is_floating_point_v<M>) {
      member = static_cast<M>(v);
    } else {
      member = static_cast<M>(static_cast<std::int64_t>(std::nearbyint(v)));
    }
  }

  const MessageCodec* message_ = nullptr;
  std::array<std::uint8_t, kFieldCount> index_{};
  bool integers_ = false;  // kIntegerFields on a plain_integers() message
};

enum class FttKind : std::uint8_t { kTrigger, kSync, kAsync };

/// How a message takes part in FTT-CAN, from the DBC attributes FttKind,
/// FttIndex, GenMsgCycleTime (period) and GenMsgDelayTime (minimum gap).
struct FttInfo {
  FttKind kind = FttKind::kAsync;
  int index = -1;    ///< bit in TM.sync_bitmap (synchronous messages), else -1
  Nanos period{0};   ///< trigger and synchronous messages
  Nanos min_gap{0};  ///< asynchronous messages
};

/// A message's FTT information from its DBC attributes (`file` names the DBC
/// in errors). Throws DbcError naming the attribute to set.
FttInfo read_ftt(const MessageDef& m, const std::string& file);

/// The whole contract: a Codec plus typed bindings and FTT information for
/// every message canhil uses. Immutable and shared between nodes.
class MessageSet {
 public:
  /// Checks the FTT attributes (one trigger message, unique FttIndex 0..31,
  /// positive periods) and binds every typed message. Throws DbcError.
  static std::shared_ptr<const MessageSet> create(Database db);
  static std::shared_ptr<const MessageSet> load(const std::filesystem::path& path);

  MessageSet(const MessageSet&) = delete;
  MessageSet& operator=(const MessageSet&) = delete;

  const Codec& codec() const noexcept { return codec_; }
  /// FTT information of a message of codec().
  const FttInfo& ftt(const MessageCodec& m) const noexcept;
  /// Synchronous message with this FTT index, or nullptr.
  const MessageCodec* sync_message(int index) const noexcept;

  TypedCodec<Tm> tm;
  TypedCodec<M1> m1;
  std::array<TypedCodec<M3>, 3> m3;  ///< M3_1..M3_3
  TypedCodec<M4_1> m4_1;
  TypedCodec<M4_2> m4_2;
  TypedCodec<M5_1> m5_1;
  TypedCodec<M5_2> m5_2;
  TypedCodec<M6_1> m6_1;
  TypedCodec<M6_2> m6_2;
  TypedCodec<M7> m7;
  TypedCodec<M2> m2;
  TypedCodec<M8> m8;
  TypedCodec<M9> m9;
  TypedCodec<M10> m10;

 private:
  explicit MessageSet(Database db);
  Codec codec_;
  std::vector<FttInfo> ftt_;  // parallel to codec_.messages()
};

}  // namespace canhil::frames
