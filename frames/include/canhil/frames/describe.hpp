// canhil/frames/describe.hpp — human and JSON renderings of frames.
//
// Used by `canhil frames decode` and `canhil dump`. Pure; allocates strings.
#pragma once

#include <string>

#include "canhil/frames/codec.hpp"

namespace canhil::frames {

/// One frame decoded against a codec, with everything a viewer reports.
struct Described {
  const MessageCodec* message = nullptr;  ///< nullptr: unknown id, error frame
  DecodeResult result;
  std::array<double, kMaxSignals> values{};
};

Described describe(const Codec& codec, const CanFrame& frame) noexcept;

/// Decimal places that show a signal's resolution (factor 0.001 -> 3).
int decimals_for(const SignalDef& signal);
/// A physical value as text with the signal's resolution (no unit).
std::string format_value(const SignalDef& signal, double value);

/// `M6_1  vx=0.500 m/s  vy=0.000 m/s`, or `[unknown id]`, `[wrong length 4, M6_1 has 8]`,
/// `[error frame: controller]`, `[remote request for M6_1]`; out-of-range
/// signals are marked `!`.
std::string describe_text(const CanFrame& frame, const Described& d);

/// One JSON object (no newline): id, name, status, signals {name: {value, unit, raw, out_of_range}}.
std::string describe_json(const CanFrame& frame, const Described& d);

/// Names of the error classes set in an error frame's id (e.g. "controller,bus-off").
std::string error_classes(std::uint32_t error_id);

/// JSON string literal with escapes.
std::string json_quote(std::string_view text);

}  // namespace canhil::frames
