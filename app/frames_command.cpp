#include <charconv>
#include <cstdio>
#include <iostream>
#include <map>

#include "canhil/frames/candump.hpp"
#include "canhil/frames/codec.hpp"
#include "canhil/frames/describe.hpp"
#include "commands.hpp"
#include "dbc_choice.hpp"

namespace canhil::app {
namespace {

using namespace canhil::frames;

std::string kind_of(const MessageDef& m) { return m.attribute_text("FttKind").value_or("-"); }

std::string timing_of(const MessageDef& m) {
  const std::string kind = kind_of(m);
  if (kind == "async") {
    const auto gap = m.attribute_int("GenMsgDelayTime").value_or(0);
    return gap > 0 ? ">=" + std::to_string(gap) + " ms" : "-";
  }
  const auto period = m.attribute_int("GenMsgCycleTime").value_or(0);
  return period > 0 ? std::to_string(period) + " ms" : "-";
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ",") + s;
  return out.empty() ? "-" : out;
}

std::string hex_id(const MessageDef& m) {
  char buf[16];
  std::snprintf(buf, sizeof buf, m.extended ? "0x%08X" : "0x%03X", m.id);
  return buf;
}

int list(const Codec& codec, bool json) {
  const Database& db = codec.database();
  if (json) {
    std::cout << "[";
    bool first = true;
    for (const auto& m : db.messages) {
      std::cout << (first ? "" : ",") << "\n  {\"name\":" << json_quote(m.name) << ",\"id\":" << m.id
                << ",\"extended\":" << (m.extended ? "true" : "false") << ",\"length\":" << int{m.length}
                << ",\"kind\":" << json_quote(kind_of(m))
                << ",\"period_ms\":" << m.attribute_int("GenMsgCycleTime").value_or(0)
                << ",\"min_gap_ms\":" << m.attribute_int("GenMsgDelayTime").value_or(0)
                << ",\"ftt_index\":" << m.attribute_int("FttIndex").value_or(-1)
                << ",\"transmitter\":" << json_quote(m.transmitter) << ",\"signals\":[";
      for (std::size_t i = 0; i < m.signals.size(); ++i) {
        std::cout << (i ? "," : "") << json_quote(m.signals[i].name);
      }
      std::cout << "]}";
      first = false;
    }
    std::cout << "\n]\n";
    return 0;
  }
  std::printf("%-7s %-6s %-4s %-8s %-9s %-4s %s\n", "message", "id", "len", "kind", "period", "ftt",
              "transmitter -> receivers");
  for (const auto& m : db.messages) {
    const auto index = m.attribute_int("FttIndex").value_or(-1);
    std::printf("%-7s %-6s %-4d %-8s %-9s %-4s %s -> %s\n", m.name.c_str(), hex_id(m).c_str(), int{m.length},
                kind_of(m).c_str(), timing_of(m).c_str(), index >= 0 ? std::to_string(index).c_str() : "-",
                m.transmitter.empty() ? "-" : m.transmitter.c_str(), join(m.receivers()).c_str());
  }
  std::printf("%zu messages from %s\n", db.messages.size(), db.file.c_str());
  return 0;
}

double parse_value(const SignalDef& s, const std::string& text) {
  for (const auto& [raw, name] : s.value_names) {  // VAL_ descriptions are accepted by name
    if (name == text) return static_cast<double>(raw) * s.factor + s.offset;
  }
  double v = 0;
  const auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || p != text.data() + text.size()) {
    throw UsageError("value \"" + text + "\" of " + s.name + " is not a number");
  }
  return v;
}

int encode(const Codec& codec, const std::vector<std::string>& words) {
  if (words.size() < 3) throw UsageError("frames encode needs a message name, e.g. frames encode M6_1 vx=0.5 vy=0");
  const MessageCodec* mc = codec.find(words[2]);
  if (mc == nullptr) throw UsageError("no message named " + words[2] + " (see canhil frames list)");
  std::array<double, kMaxSignals> values{};
  const auto init = mc->initial_values();
  std::copy(init.begin(), init.end(), values.begin());
  for (std::size_t i = 3; i < words.size(); ++i) {
    const auto eq = words[i].find('=');
    if (eq == std::string::npos) throw UsageError("expected SIGNAL=VALUE, got \"" + words[i] + "\"");
    const std::string name = words[i].substr(0, eq);
    const auto index = mc->index_of(name);
    if (!index) {
      std::string names;
      for (const auto& s : mc->def().signals) names += (names.empty() ? "" : ", ") + s.name;
      throw UsageError(mc->def().name + " has no signal " + name + "; its signals are " + names);
    }
    values[*index] = parse_value(mc->def().signals[*index], words[i].substr(eq + 1));
  }
  CanFrame frame;
  const EncodeResult r = mc->encode(std::span<const double>(values.data(), mc->signal_count()), frame);
  std::printf("%s\n", format_compact(frame).c_str());
  for (std::size_t i = 0; i < mc->signal_count(); ++i) {
    if ((r.saturated >> i) & 1u) {
      const SignalDef& s = mc->def().signals[i];
      std::fprintf(stderr, "canhil: %s=%g is outside [%g, %g] %s; saturated\n", s.name.c_str(), values[i], s.minimum,
                   s.maximum, s.unit.c_str());
    }
  }
  return r.ok() ? 0 : 1;
}

int decode(const Codec& codec, const std::vector<std::string>& words, bool json) {
  if (words.size() < 3) throw UsageError("frames decode needs at least one frame, e.g. 131#F401000000000000");
  int status = 0;
  for (std::size_t i = 2; i < words.size(); ++i) {
    CanFrame frame;
    std::string error;
    if (!parse_compact(words[i], frame, &error)) {
      std::fprintf(stderr, "canhil: %s\n", error.c_str());
      status = 1;
      continue;
    }
    const Described d = describe(codec, frame);
    if (json) {
      std::printf("%s\n", describe_json(frame, d).c_str());
    } else {
      std::printf("%s  %s\n", format_compact(frame).c_str(), describe_text(frame, d).c_str());
    }
    if (frame.kind == FrameKind::kData && !d.result.ok()) status = 1;
  }
  return status;
}

}  // namespace

int run_frames(Args& args, const std::optional<std::string>& dbc) {
  const bool json = args.flag("--json");
  const std::vector<std::string> words = args.positionals();
  if (words.size() < 2) throw UsageError("frames needs list, encode or decode");
  const Codec codec(load_chosen_dbc(dbc));
  const std::string& sub = words[1];
  if (sub == "list") return list(codec, json);
  if (sub == "encode") return encode(codec, words);
  if (sub == "decode") return decode(codec, words, json);
  throw UsageError("unknown frames subcommand \"" + sub + "\"");
}

}  // namespace canhil::app
