#include "canhil/frames/candump.hpp"

#include <cstdio>
#include <cstring>

namespace canhil::frames {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool fail(std::string* error, const char* what, std::string_view text) {
  if (error != nullptr) {
    *error = std::string(what) + " in \"" + std::string(text) + "\"";
  }
  return false;
}

constexpr char kHexUpper[] = "0123456789ABCDEF";
constexpr std::int64_t kMaxLogSeconds = 9'000'000'000;

}  // namespace

bool parse_compact(std::string_view text, CanFrame& out, std::string* error) {
  out = CanFrame{};
  const std::size_t hash = text.find('#');
  if (hash == std::string_view::npos) return fail(error, "no '#' between identifier and data", text);
  if (hash + 1 < text.size() && text[hash + 1] == '#') {
    return fail(error, "CAN FD frames ('##') are not supported", text);
  }
  if (hash != 3 && hash != 8) {
    return fail(error, "identifier must have 3 (standard) or 8 (extended) hex digits", text);
  }
  std::uint32_t id = 0;
  for (std::size_t i = 0; i < hash; ++i) {
    const int v = hex_value(text[i]);
    if (v < 0) return fail(error, "identifier is not hexadecimal", text);
    id = (id << 4) | static_cast<std::uint32_t>(v);
  }
  if (hash == 3) {
    if (id > kStandardIdMask) return fail(error, "standard identifier above 7FF", text);
    out.id = id;
  } else if ((id & kErrorFlag) != 0u) {
    out.kind = FrameKind::kError;
    out.id = id & kErrorClassMask;
  } else {
    if (id > kExtendedIdMask) return fail(error, "extended identifier above 1FFFFFFF", text);
    out.id = id;
    out.extended = true;
  }

  std::size_t pos = hash + 1;
  if (pos < text.size() && (text[pos] == 'R' || text[pos] == 'r')) {
    if (out.kind == FrameKind::kError) return fail(error, "an error frame cannot be a remote frame", text);
    out.kind = FrameKind::kRemote;
    ++pos;
    if (pos < text.size()) {
      const char c = text[pos];
      if (c < '0' || c > '8') return fail(error, "remote frame length must be one digit 0..8", text);
      out.len = static_cast<std::uint8_t>(c - '0');
      ++pos;
    }
    if (pos != text.size()) return fail(error, "unexpected characters after remote frame", text);
    return true;
  }

  while (pos < text.size()) {
    const char c = text[pos];
    if (c == '.') {
      ++pos;
      continue;
    }
    if (c == '_') break;
    if (pos + 1 >= text.size()) return fail(error, "data has an odd number of hex digits", text);
    const int hi = hex_value(c);
    const int lo = hex_value(text[pos + 1]);
    if (hi < 0 || lo < 0) return fail(error, "data is not hexadecimal", text);
    if (out.len == kMaxDataBytes) return fail(error, "more than 8 data bytes", text);
    out.data[out.len++] = static_cast<std::uint8_t>((hi << 4) | lo);
    pos += 2;
  }
  if (pos < text.size()) {  // "_X": raw DLC of a classic frame with 8 bytes
    if (out.len != kMaxDataBytes || pos + 2 != text.size()) {
      return fail(error, "'_' DLC suffix needs 8 data bytes and one hex digit 9..F", text);
    }
    const int dlc = hex_value(text[pos + 1]);
    if (dlc < 9) return fail(error, "'_' DLC suffix needs one hex digit 9..F", text);
    out.len8_dlc = static_cast<std::uint8_t>(dlc);
  }
  if (out.kind == FrameKind::kError && out.len != kMaxDataBytes) {
    return fail(error, "an error frame carries 8 data bytes", text);
  }
  return true;
}

std::size_t format_compact(const CanFrame& frame, char (&buf)[kCompactMaxChars]) {
  std::size_t n = 0;
  auto put_hex = [&](std::uint32_t value, int digits) {
    for (int d = digits - 1; d >= 0; --d) {
      buf[n++] = kHexUpper[(value >> (4 * d)) & 0xFu];
    }
  };
  if (frame.kind == FrameKind::kError) {
    put_hex((frame.id & kErrorClassMask) | kErrorFlag, 8);
  } else if (frame.extended) {
    put_hex(frame.id & kExtendedIdMask, 8);
  } else {
    put_hex(frame.id & kStandardIdMask, 3);
  }
  buf[n++] = '#';
  const std::size_t len = frame.len > kMaxDataBytes ? kMaxDataBytes : frame.len;
  if (frame.kind == FrameKind::kRemote) {
    buf[n++] = 'R';
    if (len > 0) buf[n++] = kHexUpper[len];
  } else {
    for (std::size_t i = 0; i < len; ++i) put_hex(frame.data[i], 2);
    if (len == kMaxDataBytes && frame.len8_dlc > 8 && frame.len8_dlc <= 15) {
      buf[n++] = '_';
      buf[n++] = kHexUpper[frame.len8_dlc];
    }
  }
  buf[n] = '\0';
  return n;
}

std::string format_compact(const CanFrame& frame) {
  char buf[kCompactMaxChars];
  const std::size_t n = format_compact(frame, buf);
  return std::string(buf, n);
}

bool parse_log_line(std::string_view line, LogEntry& out, std::string* error) {
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) {
    line.remove_suffix(1);
  }
  if (line.empty() || line.front() != '(') return fail(error, "log line must start with '(' timestamp", line);
  const std::size_t close = line.find(')');
  if (close == std::string_view::npos) return fail(error, "timestamp has no closing ')'", line);
  const std::string_view stamp = line.substr(1, close - 1);
  const std::size_t dot = stamp.find('.');
  if (dot == std::string_view::npos || dot == 0 || stamp.size() - dot - 1 != 6) {
    return fail(error, "timestamp must be SECONDS.MICROSECONDS with 6 fraction digits", line);
  }
  std::int64_t seconds = 0;
  std::int64_t micros = 0;
  for (std::size_t i = 0; i < stamp.size(); ++i) {
    if (i == dot) continue;
    const char c = stamp[i];
    if (c < '0' || c > '9') return fail(error, "timestamp is not a decimal number", line);
    if (i < dot) {
      seconds = seconds * 10 + (c - '0');
      // Nanoseconds in int64 reach about 9.2e9 s (year 2262).
      if (seconds > kMaxLogSeconds) return fail(error, "timestamp too large (beyond the year 2262)", line);
    } else {
      micros = micros * 10 + (c - '0');
    }
  }
  std::string_view rest = line.substr(close + 1);
  const std::size_t iface_start = rest.find_first_not_of(" \t");
  if (iface_start == std::string_view::npos) return fail(error, "no interface name after timestamp", line);
  rest.remove_prefix(iface_start);
  const std::size_t iface_end = rest.find_first_of(" \t");
  if (iface_end == std::string_view::npos) return fail(error, "no frame after interface name", line);
  const std::string_view iface = rest.substr(0, iface_end);
  rest.remove_prefix(iface_end);
  const std::size_t frame_start = rest.find_first_not_of(" \t");
  if (frame_start == std::string_view::npos) return fail(error, "no frame after interface name", line);
  rest.remove_prefix(frame_start);
  // candump -x style direction/flags after the frame (" T", " R") are accepted and ignored.
  const std::size_t frame_end = rest.find_first_of(" \t");
  std::string_view frame_text = rest.substr(0, frame_end);
  if (frame_end != std::string_view::npos) {
    std::string_view tail = rest.substr(frame_end);
    tail.remove_prefix(tail.find_first_not_of(" \t"));
    if (tail != "T" && tail != "R") return fail(error, "unexpected text after the frame", line);
  }
  if (!parse_compact(frame_text, out.frame, error)) return false;
  out.time = std::chrono::seconds(seconds) + std::chrono::microseconds(micros);
  out.iface.assign(iface);
  return true;
}

std::string format_log_line(Nanos time, std::string_view iface, const CanFrame& frame) {
  const auto micros_total = std::chrono::duration_cast<std::chrono::microseconds>(time).count();
  const long long secs = micros_total / 1'000'000;
  const long long micros = micros_total % 1'000'000;
  char stamp[40];
  std::snprintf(stamp, sizeof stamp, "(%010lld.%06lld) ", secs, micros);
  char compact[kCompactMaxChars];
  format_compact(frame, compact);
  std::string out(stamp);
  out.append(iface);
  out.push_back(' ');
  out.append(compact);
  return out;
}

}  // namespace canhil::frames
