// libFuzzer target: frames from arbitrary bytes through the shipped codec and
// the text renderers, and the input as candump text through both parsers.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "canhil/frames/candump.hpp"
#include "canhil/frames/codec.hpp"
#include "canhil/frames/describe.hpp"

namespace {
const canhil::frames::Codec& shipped() {
  static const auto codec = std::make_unique<canhil::frames::Codec>(canhil::frames::load_dbc(CANHIL_FUZZ_DBC));
  return *codec;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace canhil::frames;
  const Codec& codec = shipped();
  if (size >= 3) {
    CanFrame f;
    f.id = (static_cast<std::uint32_t>(data[0]) << 8 | data[1]) & 0x7FF;
    f.len = static_cast<std::uint8_t>(data[2] % 9);
    const std::size_t n = std::min<std::size_t>(size - 3, 8);
    std::memcpy(f.data.data(), data + 3, n);
    if (n < f.len) f.len = static_cast<std::uint8_t>(n);
    const Described d = describe(codec, f);
    (void)describe_text(f, d);
    (void)describe_json(f, d);
  }
  const std::string text(reinterpret_cast<const char*>(data), size);
  CanFrame parsed;
  std::string error;
  if (parse_compact(text, parsed, &error)) {
    CanFrame again;
    if (!parse_compact(format_compact(parsed), again) || !(again == parsed)) __builtin_trap();  // round trip
  }
  LogEntry entry;
  (void)parse_log_line(text, entry, &error);
  return 0;
}
