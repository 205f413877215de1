// canhil/frames/codec.hpp — signal codec with layouts precomputed at load.
//
// Encoding and decoding touch no socket, clock or global and never allocate:
// values travel in caller-provided spans of doubles, one per signal in DBC
// order. Intel and Motorola byte order, signed and unsigned integers, IEEE
// float32/float64 (SIG_VALTYPE_), factor and offset. Thread-safe: a Codec is
// immutable after construction.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "canhil/frames/dbc.hpp"
#include "canhil/frames/frame.hpp"

namespace canhil::frames {

/// At most one signal per payload bit.
inline constexpr std::size_t kMaxSignals = 64;

enum class DecodeStatus : std::uint8_t {
  kOk,           ///< all signals decoded (some may still be out of range, see DecodeResult)
  kWrongLength,  ///< frame length differs from the message's; nothing decoded
  kNotData,      ///< remote or error frame; nothing decoded
  kUnknownId,    ///< (Codec::decode only) no message has this id
};

struct DecodeResult {
  DecodeStatus status = DecodeStatus::kOk;
  /// Bit i set: signal i's raw value lies outside the DBC's [minimum|maximum].
  std::uint64_t out_of_range = 0;
  bool ok() const noexcept { return status == DecodeStatus::kOk && out_of_range == 0; }
};

struct EncodeResult {
  /// Bit i set: signal i was outside its range (or not finite) and was saturated.
  std::uint64_t saturated = 0;
  bool ok() const noexcept { return saturated == 0; }
};

/// One signal's layout, precomputed from its SignalDef.
struct SignalLayout {
  std::uint64_t mask = 0;  ///< `length` low bits set
  std::uint8_t shift = 0;  ///< LSB position in the little-endian (Intel) or big-endian (Motorola) word
  std::uint8_t length = 0;
  bool motorola = false;
  ValueType type = ValueType::kUnsigned;
  double factor = 1.0;
  /// 1/factor when that is a whole number (decimal factors such as 0.001): then
  /// value = raw / divisor, which rounds correctly (314159 / 1e5 = 3.14159),
  /// where raw * 1e-5 would not. 0 otherwise.
  double divisor = 0.0;
  double offset = 0.0;
  std::int64_t raw_min = 0;  ///< integer signals: allowed raw range (declared range ∩ representable)
  std::int64_t raw_max = 0;
  double phys_min = 0.0;  ///< float signals: declared range (both 0: none)
  double phys_max = 0.0;
  double initial = 0.0;  ///< physical value used when a caller sets nothing (GenSigStartValue or 0)
};

class MessageCodec {
 public:
  explicit MessageCodec(const MessageDef& def);

  const MessageDef& def() const noexcept { return *def_; }
  std::uint32_t id() const noexcept { return def_->id; }
  std::string_view name() const noexcept { return def_->name; }
  std::size_t signal_count() const noexcept { return layouts_.size(); }
  const SignalLayout& layout(std::size_t i) const noexcept { return layouts_[i]; }
  /// Index of a signal in DBC order, or nullopt.
  std::optional<std::size_t> index_of(std::string_view signal) const noexcept;
  /// Initial physical values, one per signal: start from these when encoding.
  std::span<const double> initial_values() const noexcept { return initial_; }

  /// Decodes into `out` (size >= signal_count()). Frames of the wrong length or
  /// kind are reported and not decoded.
  DecodeResult decode(const CanFrame& frame, std::span<double> out) const noexcept;
  /// Raw (unscaled) integer value of signal i in `frame`; for float signals the bit pattern.
  std::uint64_t raw_bits(const CanFrame& frame, std::size_t i) const noexcept;
  /// Encodes `values` (size >= signal_count()) into a data frame of this message's id and length.
  EncodeResult encode(std::span<const double> values, CanFrame& out) const noexcept;

  /// True when every signal is an integer of at most 53 bits with factor 1
  /// and offset 0: its physical value is its raw value, and the two calls
  /// below give what decode() and encode() give, without doubles.
  bool plain_integers() const noexcept { return plain_integers_; }
  /// decode() for plain_integers() messages: the values as integers.
  DecodeResult decode_integers(const CanFrame& frame, std::span<std::int64_t> out) const noexcept;
  /// encode() for plain_integers() messages: values outside a signal's range are saturated to it.
  EncodeResult encode_integers(std::span<const std::int64_t> values, CanFrame& out) const noexcept;
  /// initial_values() as integers (plain_integers() messages; empty otherwise).
  std::span<const std::int64_t> initial_integers() const noexcept { return initial_integers_; }

 private:
  /// kOk when `frame` is a data frame of this message's length, else why not.
  DecodeStatus refusal(const CanFrame& frame) const noexcept;
  void put_frame(std::uint64_t le, std::uint64_t be, CanFrame& out) const noexcept;

  const MessageDef* def_;
  std::vector<SignalLayout> layouts_;
  std::vector<double> initial_;
  bool plain_integers_ = false;
  std::vector<std::int64_t> initial_integers_;
};

/// Whether a received frame is `message`: a data frame with its identifier,
/// standard or extended as the DBC declares it. The one rule every receiver
/// (the nodes, canhil-hwcomm) asks. Its length is not asked: a frame of the
/// message with the wrong length is still that message, a bad one
/// (decode() says kWrongLength, and the receiver counts it); a remote frame
/// with the message's id is not the message.
inline bool is_message(const CanFrame& frame, const MessageCodec& message) noexcept {
  return frame.kind == FrameKind::kData && frame.id == message.id() && frame.extended == message.def().extended;
}

/// The codec for a whole database; owns the Database it was built from.
/// Non-copyable; moving keeps every MessageCodec pointer valid.
class Codec {
 public:
  explicit Codec(Database db);
  Codec(const Codec&) = delete;
  Codec& operator=(const Codec&) = delete;
  Codec(Codec&&) noexcept = default;
  Codec& operator=(Codec&&) noexcept = default;
  ~Codec() = default;

  const Database& database() const noexcept { return *db_; }
  std::span<const MessageCodec> messages() const noexcept { return messages_; }
  /// O(1) for standard ids; nullptr when no message has this id.
  const MessageCodec* find(std::uint32_t id, bool extended = false) const noexcept;
  const MessageCodec* find(std::string_view name) const noexcept;

  /// Looks the frame's message up and decodes it; kUnknownId when none matches.
  DecodeResult decode(const CanFrame& frame, std::span<double> out,
                      const MessageCodec** message = nullptr) const noexcept;

 private:
  std::unique_ptr<Database> db_;  // heap-held so MessageDef pointers survive moves
  std::vector<MessageCodec> messages_;
  std::vector<std::int16_t> standard_index_;  // 2048 entries, -1 = none
};

}  // namespace canhil::frames
