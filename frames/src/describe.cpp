#include "canhil/frames/describe.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "canhil/frames/candump.hpp"

namespace canhil::frames {

Described describe(const Codec& codec, const CanFrame& frame) noexcept {
  Described d;
  if (frame.kind == FrameKind::kData) {
    d.result = codec.decode(frame, d.values, &d.message);
  } else if (frame.kind == FrameKind::kRemote) {
    d.message = codec.find(frame.id, frame.extended);
    d.result.status = DecodeStatus::kNotData;
  } else {
    d.result.status = DecodeStatus::kNotData;
  }
  return d;
}

int decimals_for(const SignalDef& signal) {
  if (signal.value_type == ValueType::kFloat32 || signal.value_type == ValueType::kFloat64) return 6;
  const double f = std::fabs(signal.factor);
  if (f >= 1.0 && std::floor(f) == f && std::floor(signal.offset) == signal.offset) return 0;
  int d = static_cast<int>(std::ceil(-std::log10(f) - 1e-9));
  return d < 0 ? 0 : (d > 9 ? 9 : d);
}

std::string format_value(const SignalDef& signal, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals_for(signal), value);
  std::string s(buf);
  if (s == "-0" || s.rfind("-0.", 0) == 0) {  // avoid "-0.000"
    bool all_zero = true;
    for (char c : s) all_zero = all_zero && (c == '-' || c == '0' || c == '.');
    if (all_zero) s.erase(0, 1);
  }
  return s;
}

std::string error_classes(std::uint32_t error_id) {
  static constexpr const char* kNames[] = {"tx-timeout", "lost-arbitration", "controller", "protocol",  "transceiver",
                                           "no-ack",     "bus-off",          "bus-error",  "restarted", "counters"};
  std::string out;
  for (unsigned i = 0; i < std::size(kNames); ++i) {
    if ((error_id & (1u << i)) != 0u) {
      if (!out.empty()) out += ',';
      out += kNames[i];
    }
  }
  return out.empty() ? "unspecified" : out;
}

namespace {

// The names of the set bits of `bits`, in order, comma-separated.
std::string bit_names(std::uint8_t bits, std::initializer_list<const char*> names) {
  std::string out;
  unsigned i = 0;
  for (const char* name : names) {
    if ((bits & (1u << i++)) != 0u) out += (out.empty() ? "" : ",") + std::string(name);
  }
  return out;
}

// CAN_ERR_PROT_LOC_* as words.
const char* location_name(std::uint8_t location) {
  switch (location) {
    case kProtocolLocationSof:
      return "start of frame";
    case kProtocolLocationId28To21:
    case kProtocolLocationId20To18:
    case kProtocolLocationId17To13:
    case kProtocolLocationId12To05:
    case kProtocolLocationId04To00:
      return "identifier";
    case kProtocolLocationSrtr:
      return "SRR";
    case kProtocolLocationIde:
      return "IDE";
    case kProtocolLocationRtr:
      return "RTR";
    case kProtocolLocationRes1:
    case kProtocolLocationRes0:
      return "reserved bit";
    case kProtocolLocationDlc:
      return "DLC";
    case kProtocolLocationData:
      return "data";
    case kProtocolLocationCrc:
      return "CRC";
    case kProtocolLocationCrcDelimiter:
      return "CRC delimiter";
    case kProtocolLocationAck:
      return "ACK slot";
    case kProtocolLocationAckDelimiter:
      return "ACK delimiter";
    case kProtocolLocationEof:
      return "end of frame";
    case kProtocolLocationIntermission:
      return "intermission";
    default:
      return nullptr;
  }
}

// What an error frame's data says (linux/can/error.h): the controller's
// state, the protocol error's kind and place, the counters.
std::string error_details(const CanFrame& f) {
  std::string out;
  auto add = [&out](const std::string& part) {
    if (!part.empty()) out += "; " + part;
  };
  if ((f.id & kErrorClassController) != 0u) {
    add(bit_names(f.data[1],
                  {"rx-overflow", "tx-overflow", "rx-warning", "tx-warning", "rx-passive", "tx-passive", "active"}));
  }
  if ((f.id & kErrorClassProtocol) != 0u) {
    std::string kind = bit_names(f.data[2], {"bit", "form", "stuff", "bit0", "bit1", "overload", "active", "tx"});
    if (const char* where = location_name(f.data[3]))
      kind += (kind.empty() ? "" : " ") + std::string("in the ") + where;
    add(kind);
  }
  if ((f.id & kErrorClassCounters) != 0u) {
    add("TEC " + std::to_string(f.data[6]) + " REC " + std::to_string(f.data[7]));
  }
  return out;
}

}  // namespace

std::string describe_text(const CanFrame& frame, const Described& d) {
  if (frame.kind == FrameKind::kError) return "[error frame: " + error_classes(frame.id) + error_details(frame) + "]";
  if (d.message == nullptr) return "[unknown id]";
  const MessageDef& m = d.message->def();
  if (frame.kind == FrameKind::kRemote) return "[remote request for " + m.name + "]";
  if (d.result.status == DecodeStatus::kWrongLength) {
    return "[wrong length " + std::to_string(frame.len) + ", " + m.name + " has " + std::to_string(m.length) + "]";
  }
  std::string out = m.name;
  for (std::size_t i = 0; i < m.signals.size(); ++i) {
    const SignalDef& s = m.signals[i];
    out += "  " + s.name + "=" + format_value(s, d.values[i]);
    if (!s.unit.empty()) out += " " + s.unit;
    const auto raw = static_cast<std::int64_t>(std::llround((d.values[i] - s.offset) / s.factor));
    if (const auto it = s.value_names.find(raw); it != s.value_names.end()) out += " (" + it->second + ")";
    if ((d.result.out_of_range & (std::uint64_t{1} << i)) != 0u) out += " !out-of-range";
  }
  return out;
}

std::string json_quote(std::string_view text) {
  std::string out = "\"";
  for (char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

std::string describe_json(const CanFrame& frame, const Described& d) {
  char idbuf[16];
  std::snprintf(idbuf, sizeof idbuf, frame.extended ? "0x%08X" : "0x%03X", frame.id);
  std::string out = "{\"frame\":" + json_quote(format_compact(frame)) + ",\"id\":" + json_quote(idbuf);
  auto status = [&]() -> std::string {
    if (frame.kind == FrameKind::kError) return "error_frame";
    if (frame.kind == FrameKind::kRemote) return "remote";
    if (d.message == nullptr) return "unknown_id";
    if (d.result.status == DecodeStatus::kWrongLength) return "wrong_length";
    return d.result.out_of_range != 0u ? "out_of_range" : "ok";
  }();
  if (d.message != nullptr) out += ",\"name\":" + json_quote(d.message->name());
  out += ",\"status\":" + json_quote(status);
  if (frame.kind == FrameKind::kError) out += ",\"error_classes\":" + json_quote(error_classes(frame.id));
  if (d.message != nullptr && d.result.status == DecodeStatus::kOk) {
    const MessageDef& m = d.message->def();
    out += ",\"signals\":{";
    for (std::size_t i = 0; i < m.signals.size(); ++i) {
      const SignalDef& s = m.signals[i];
      char num[64];
      const auto end = std::to_chars(num, num + sizeof num - 1, d.values[i]).ptr;  // shortest round-trip form
      *end = '\0';
      if (i > 0) out += ',';
      out += json_quote(s.name) + ":{\"value\":" + num + ",\"unit\":" + json_quote(s.unit) +
             ",\"raw\":" + std::to_string(d.message->raw_bits(frame, i)) +
             ",\"out_of_range\":" + (((d.result.out_of_range >> i) & 1u) != 0u ? "true" : "false") + "}";
    }
    out += "}";
  }
  return out + "}";
}

}  // namespace canhil::frames
