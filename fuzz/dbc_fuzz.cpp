// libFuzzer target: the DBC parser, then the codec built from whatever parsed.
// Any input must either parse or throw DbcError; nothing may crash, leak or
// trip a sanitizer.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "canhil/frames/codec.hpp"
#include "canhil/frames/dbc.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    canhil::frames::Codec codec(canhil::frames::parse_dbc(text, "fuzz.dbc"));
    std::array<double, canhil::frames::kMaxSignals> values{};
    for (const auto& m : codec.messages()) {
      canhil::frames::CanFrame f;
      m.encode(m.initial_values(), f);
      m.decode(f, values);
      f.data.fill(0xA5);
      m.decode(f, values);
    }
  } catch (const canhil::frames::DbcError&) {
  }
  return 0;
}
