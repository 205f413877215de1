#include <algorithm>
#include <cmath>

#include "dbc_parser.hpp"

namespace canhil::frames::dbc_detail {

void Parser::check_message(const MessageDef& m) {
  // Bit occupancy in the 64-bit payload, in Intel numbering (bit k = byte k/8, bit k%8).
  std::vector<const SignalDef*> owner(64, nullptr);
  for (const auto& s : m.signals) {
    std::vector<int> bits;
    bits.reserve(s.length);
    if (s.byte_order == ByteOrder::kIntel) {
      for (int i = 0; i < s.length; ++i) bits.push_back(s.start_bit + i);
    } else {
      // Motorola: start bit is the MSB; walk towards the LSB in sawtooth order.
      int bit = s.start_bit;
      for (int i = 0; i < s.length; ++i) {
        bits.push_back(bit);
        if (bit % 8 == 0) {
          bit += 15;
        } else {
          --bit;
        }
      }
    }
    for (int b : bits) {
      if (b < 0 || b >= m.length * 8) {
        error("signal " + s.name + " (start bit " + std::to_string(s.start_bit) + ", " + std::to_string(s.length) +
                  " bits) runs past the " + std::to_string(m.length) + "-byte message " + m.name +
                  "; fix the start bit, the length or the message length",
              s.line);
      }
      const SignalDef*& o = owner[static_cast<std::size_t>(b)];
      if (o != nullptr) {
        error("signals " + o->name + " and " + s.name + " of " + m.name + " overlap at bit " + std::to_string(b) +
                  "; move one of them",
              s.line);
      }
      o = &s;
    }
    check_range(m, s);
  }
}

// An integer signal's declared physical range, mapped through its factor and
// offset, must meet the raw values its bits can hold; otherwise every value
// would be out of range (a factor, offset or range typed wrong).
void Parser::check_range(const MessageDef& m, const SignalDef& s) {
  if (s.value_type == ValueType::kFloat32 || s.value_type == ValueType::kFloat64 || !s.has_range()) return;
  const double bits_lo = s.value_type == ValueType::kSigned ? -std::ldexp(1.0, s.length - 1) : 0.0;
  const double bits_hi =
      s.value_type == ValueType::kSigned ? std::ldexp(1.0, s.length - 1) - 1 : std::ldexp(1.0, s.length) - 1;
  double a = (s.minimum - s.offset) / s.factor;
  double b = (s.maximum - s.offset) / s.factor;
  if (a > b) std::swap(a, b);
  const double slack = 1e-6 * std::max({1.0, std::fabs(a), std::fabs(b)});
  if (!std::isfinite(a) || !std::isfinite(b) || b + slack < bits_lo || a - slack > bits_hi) {
    char range[160];
    std::snprintf(range, sizeof range, "[%g|%g] with factor %g and offset %g", s.minimum, s.maximum, s.factor,
                  s.offset);
    error("signal " + s.name + " of " + m.name + ": its range " + range + " lies outside what its " +
              std::to_string(s.length) + (s.value_type == ValueType::kSigned ? " signed" : " unsigned") +
              " bits can hold; fix the factor, the offset or the range",
          s.line);
  }
}

void Parser::check_database() {
  for (const auto& m : db_.messages) check_message(m);
}

}  // namespace canhil::frames::dbc_detail
