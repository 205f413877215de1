#include "canhil/frames/codec.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

namespace canhil::frames {
namespace {

static_assert(std::endian::native == std::endian::little, "canhil's codec assumes a little-endian host");

std::uint64_t load_le(const CanFrame& f) noexcept {
  std::uint64_t w = 0;
  std::memcpy(&w, f.data.data(), sizeof w);  // bytes past len are zero in frames canhil builds
  if (f.len < 8) w &= f.len == 0 ? 0 : (~std::uint64_t{0} >> (64 - 8 * f.len));
  return w;
}

// A payload as both byte orders' words: a signal's bits are a shift and a mask of one.
struct Payload {
  std::uint64_t le;  // Intel
  std::uint64_t be;  // Motorola
};
Payload payload_of(const CanFrame& f) noexcept {
  const std::uint64_t le = load_le(f);
  return {le, __builtin_bswap64(le)};
}
std::uint64_t raw_of(const SignalLayout& l, const Payload& p) noexcept {
  return ((l.motorola ? p.be : p.le) >> l.shift) & l.mask;
}

std::int64_t sign_extend(std::uint64_t raw, unsigned length) noexcept {
  if (length >= 64) return static_cast<std::int64_t>(raw);
  const std::uint64_t sign = std::uint64_t{1} << (length - 1);
  return static_cast<std::int64_t>((raw ^ sign) - sign);
}

// A double as int64, saturated at both ends; NaN reads as 0. (A plain cast of
// a value outside int64's range is undefined, and a DBC's numbers are user input.)
std::int64_t saturate_int64(double v) noexcept {
  constexpr double kTwo63 = 9223372036854775808.0;  // 2^63, exact in double
  if (std::isnan(v)) return 0;
  if (v >= kTwo63) return std::numeric_limits<std::int64_t>::max();
  if (v < -kTwo63) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(v);
}

std::int64_t read_start_value(const SignalDef& s) {
  const auto it = s.attributes.find("GenSigStartValue");
  if (it == s.attributes.end()) return 0;
  if (const auto* i = std::get_if<std::int64_t>(&it->second)) return *i;
  if (const auto* d = std::get_if<double>(&it->second)) return saturate_int64(*d);
  return 0;
}

}  // namespace

MessageCodec::MessageCodec(const MessageDef& def) : def_(&def) {
  layouts_.reserve(def.signals.size());
  for (const SignalDef& s : def.signals) {
    SignalLayout l;
    l.length = static_cast<std::uint8_t>(s.length);
    l.mask = s.length >= 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << s.length) - 1);
    l.motorola = s.byte_order == ByteOrder::kMotorola;
    if (l.motorola) {
      const int msb = (7 - s.start_bit / 8) * 8 + s.start_bit % 8;
      l.shift = static_cast<std::uint8_t>(msb - (s.length - 1));
    } else {
      l.shift = static_cast<std::uint8_t>(s.start_bit);
    }
    l.type = s.value_type;
    l.factor = s.factor;
    l.offset = s.offset;
    if (std::fabs(s.factor) < 1.0) {
      const double inverse = std::round(1.0 / s.factor);
      if (std::fabs(inverse * s.factor - 1.0) < 1e-12) l.divisor = inverse;
    }
    if (l.type == ValueType::kFloat32 || l.type == ValueType::kFloat64) {
      l.phys_min = s.minimum;
      l.phys_max = s.maximum;
    } else {
      // Representable raw range, then narrowed by the declared physical range.
      double lo = 0;
      double hi = 0;
      if (l.type == ValueType::kSigned) {
        lo = -std::ldexp(1.0, s.length - 1);
        hi = std::ldexp(1.0, s.length - 1) - 1;
      } else {
        hi = std::ldexp(1.0, s.length) - 1;
      }
      if (s.has_range()) {
        double a = (s.minimum - s.offset) / s.factor;
        double b = (s.maximum - s.offset) / s.factor;
        if (a > b) std::swap(a, b);
        const double eps_a = 1e-6 * std::max(1.0, std::fabs(a));
        const double eps_b = 1e-6 * std::max(1.0, std::fabs(b));
        lo = std::max(lo, std::ceil(a - eps_a));
        hi = std::min(hi, std::floor(b + eps_b));
      }
      // 64-bit extremes are not exact in double: saturate. A declared range
      // that misses the representable one (the parser refuses it) would leave
      // lo > hi: then nothing is in range, and encoding saturates to lo.
      l.raw_min = saturate_int64(lo);
      l.raw_max = std::max(l.raw_min, saturate_int64(hi));
      if (l.type == ValueType::kUnsigned && s.length == 64) l.raw_max = std::numeric_limits<std::int64_t>::max();
    }
    l.initial = static_cast<double>(read_start_value(s)) * s.factor + s.offset;
    layouts_.push_back(l);
    initial_.push_back(l.initial);
  }
  plain_integers_ = std::all_of(layouts_.begin(), layouts_.end(), [](const SignalLayout& l) {
    return (l.type == ValueType::kUnsigned || l.type == ValueType::kSigned) && l.length <= 53 && l.factor == 1.0 &&
           l.offset == 0.0;
  });
  if (plain_integers_) {
    // What encode() makes of the initial value, before saturation: a whole number within 2^53.
    for (const double v : initial_) initial_integers_.push_back(saturate_int64(std::nearbyint(v)));
  }
}

std::optional<std::size_t> MessageCodec::index_of(std::string_view signal) const noexcept {
  for (std::size_t i = 0; i < def_->signals.size(); ++i) {
    if (def_->signals[i].name == signal) return i;
  }
  return std::nullopt;
}

std::uint64_t MessageCodec::raw_bits(const CanFrame& frame, std::size_t i) const noexcept {
  return raw_of(layouts_[i], payload_of(frame));
}

DecodeStatus MessageCodec::refusal(const CanFrame& frame) const noexcept {
  if (frame.kind != FrameKind::kData) return DecodeStatus::kNotData;
  if (frame.len != def_->length) return DecodeStatus::kWrongLength;
  return DecodeStatus::kOk;
}

DecodeResult MessageCodec::decode(const CanFrame& frame, std::span<double> out) const noexcept {
  DecodeResult r;
  r.status = refusal(frame);
  if (r.status != DecodeStatus::kOk) return r;
  const Payload payload = payload_of(frame);
  for (std::size_t i = 0; i < layouts_.size(); ++i) {
    const SignalLayout& l = layouts_[i];
    const std::uint64_t raw = raw_of(l, payload);
    double value = 0;
    switch (l.type) {
      case ValueType::kUnsigned: {
        const auto v = static_cast<std::int64_t>(raw);
        if (raw > static_cast<std::uint64_t>(l.raw_max) || v < l.raw_min) r.out_of_range |= std::uint64_t{1} << i;
        value = static_cast<double>(raw);
        break;
      }
      case ValueType::kSigned: {
        const std::int64_t v = sign_extend(raw, l.length);
        if (v < l.raw_min || v > l.raw_max) r.out_of_range |= std::uint64_t{1} << i;
        value = static_cast<double>(v);
        break;
      }
      case ValueType::kFloat32:
        value = static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(raw)));
        break;
      case ValueType::kFloat64:
        value = std::bit_cast<double>(raw);
        break;
    }
    value = (l.divisor != 0.0 ? value / l.divisor : value * l.factor) + l.offset;
    if (l.type == ValueType::kFloat32 || l.type == ValueType::kFloat64) {
      if (!std::isfinite(value) ||
          ((l.phys_min != 0.0 || l.phys_max != 0.0) && (value < l.phys_min || value > l.phys_max))) {
        r.out_of_range |= std::uint64_t{1} << i;
      }
    }
    out[i] = value;
  }
  return r;
}

EncodeResult MessageCodec::encode(std::span<const double> values, CanFrame& out) const noexcept {
  EncodeResult r;
  std::uint64_t le = 0;
  std::uint64_t be = 0;
  const std::size_t n = layouts_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const SignalLayout& l = layouts_[i];
    double phys = values[i];
    if (!std::isfinite(phys)) {
      r.saturated |= std::uint64_t{1} << i;
      phys = l.initial;
    }
    std::uint64_t raw = 0;
    if (l.type == ValueType::kFloat32 || l.type == ValueType::kFloat64) {
      if ((l.phys_min != 0.0 || l.phys_max != 0.0) && (phys < l.phys_min || phys > l.phys_max)) {
        r.saturated |= std::uint64_t{1} << i;
        phys = std::clamp(phys, l.phys_min, l.phys_max);
      }
      const double scaled = (phys - l.offset) / l.factor;
      raw = l.type == ValueType::kFloat32 ? std::bit_cast<std::uint32_t>(static_cast<float>(scaled))
                                          : std::bit_cast<std::uint64_t>(scaled);
    } else {
      const double unscaled = l.divisor != 0.0 ? (phys - l.offset) * l.divisor : (phys - l.offset) / l.factor;
      const double scaled = std::nearbyint(unscaled);
      std::int64_t v = 0;
      if (!(scaled >= static_cast<double>(l.raw_min))) {  // NaN too
        v = l.raw_min;
        r.saturated |= std::uint64_t{1} << i;
      } else if (scaled > static_cast<double>(l.raw_max)) {
        v = l.raw_max;
        r.saturated |= std::uint64_t{1} << i;
      } else {
        v = saturate_int64(scaled);
      }
      raw = static_cast<std::uint64_t>(v);
    }
    raw = (raw & l.mask) << l.shift;
    if (l.motorola) {
      be |= raw;
    } else {
      le |= raw;
    }
  }
  put_frame(le, be, out);
  return r;
}

void MessageCodec::put_frame(std::uint64_t le, std::uint64_t be, CanFrame& out) const noexcept {
  le |= __builtin_bswap64(be);
  out = CanFrame{};
  out.id = def_->id;
  out.extended = def_->extended;
  out.len = def_->length;
  std::memcpy(out.data.data(), &le, sizeof le);
  // Bytes past the length stay zero (the parser guarantees no signal reaches them).
}

DecodeResult MessageCodec::decode_integers(const CanFrame& frame, std::span<std::int64_t> out) const noexcept {
  DecodeResult r;
  r.status = refusal(frame);
  if (r.status != DecodeStatus::kOk) return r;
  const Payload payload = payload_of(frame);
  for (std::size_t i = 0; i < layouts_.size(); ++i) {
    const SignalLayout& l = layouts_[i];
    const std::uint64_t raw = raw_of(l, payload);
    // At most 53 bits: an unsigned raw value is non-negative as int64.
    const std::int64_t v = l.type == ValueType::kSigned ? sign_extend(raw, l.length) : static_cast<std::int64_t>(raw);
    if (v < l.raw_min || v > l.raw_max) r.out_of_range |= std::uint64_t{1} << i;
    out[i] = v;
  }
  return r;
}

EncodeResult MessageCodec::encode_integers(std::span<const std::int64_t> values, CanFrame& out) const noexcept {
  EncodeResult r;
  std::uint64_t le = 0;
  std::uint64_t be = 0;
  const std::size_t n = layouts_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const SignalLayout& l = layouts_[i];
    std::int64_t v = values[i];
    if (v < l.raw_min) {
      v = l.raw_min;
      r.saturated |= std::uint64_t{1} << i;
    } else if (v > l.raw_max) {
      v = l.raw_max;
      r.saturated |= std::uint64_t{1} << i;
    }
    const std::uint64_t raw = (static_cast<std::uint64_t>(v) & l.mask) << l.shift;
    if (l.motorola) {
      be |= raw;
    } else {
      le |= raw;
    }
  }
  put_frame(le, be, out);
  return r;
}

Codec::Codec(Database db) : db_(std::make_unique<Database>(std::move(db))), standard_index_(2048, -1) {
  messages_.reserve(db_->messages.size());
  for (const MessageDef& m : db_->messages) {
    if (!m.extended) standard_index_[m.id] = static_cast<std::int16_t>(messages_.size());
    messages_.emplace_back(m);
  }
}

const MessageCodec* Codec::find(std::uint32_t id, bool extended) const noexcept {
  if (!extended) {
    if (id >= standard_index_.size()) return nullptr;
    const std::int16_t i = standard_index_[id];
    return i < 0 ? nullptr : &messages_[static_cast<std::size_t>(i)];
  }
  for (const auto& m : messages_) {
    if (m.def().extended && m.id() == id) return &m;
  }
  return nullptr;
}

const MessageCodec* Codec::find(std::string_view name) const noexcept {
  for (const auto& m : messages_) {
    if (m.name() == name) return &m;
  }
  return nullptr;
}

DecodeResult Codec::decode(const CanFrame& frame, std::span<double> out, const MessageCodec** message) const noexcept {
  const MessageCodec* m = frame.kind == FrameKind::kError ? nullptr : find(frame.id, frame.extended);
  if (message != nullptr) *message = m;
  if (m == nullptr) {
    DecodeResult r;
    r.status = frame.kind == FrameKind::kError ? DecodeStatus::kNotData : DecodeStatus::kUnknownId;
    return r;
  }
  return m->decode(frame, out);
}

}  // namespace canhil::frames
