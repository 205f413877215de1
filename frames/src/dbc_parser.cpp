#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "dbc_parser.hpp"

namespace canhil::frames::dbc_detail {

Database Parser::parse() {
  db_.file = file_;
  while (true) {
    skip_ws();
    if (at_end()) break;
    const int line = line_;
    if (!is_ident_start(peek())) error("expected a section keyword (BO_, SG_, CM_, BA_, ...)" + describe_here());
    const std::string_view kw = identifier("keyword");
    if (kw != "SG_") current_ = kw == "BO_" ? current_ : nullptr;
    if (kw == "VERSION") {
      parse_version();
    } else if (kw == "NS_") {
      parse_ns();
    } else if (kw == "BS_") {
      parse_bs();
    } else if (kw == "BU_") {
      parse_bu();
    } else if (kw == "BO_") {
      parse_bo();
    } else if (kw == "SG_") {
      if (current_ == nullptr) error("SG_ outside a message; put signals right after their BO_ line", line);
      parse_sg();
    } else if (kw == "CM_") {
      parse_cm();
    } else if (kw == "BA_DEF_") {
      parse_ba_def(false);
    } else if (kw == "BA_DEF_DEF_") {
      parse_ba_def(true);
    } else if (kw == "BA_") {
      parse_ba();
    } else if (kw == "VAL_") {
      parse_val();
    } else if (kw == "SIG_VALTYPE_") {
      parse_sig_valtype();
    } else if (kw == "BO_TX_BU_") {
      parse_bo_tx_bu();
    } else if (kw == "VAL_TABLE_" || kw == "EV_" || kw == "ENVVAR_DATA_" || kw == "SGTYPE_" || kw == "SGTYPE_VAL_" ||
               kw == "BA_DEF_SGTYPE_" || kw == "BA_SGTYPE_" || kw == "SIG_TYPE_REF_" || kw == "SIG_GROUP_" ||
               kw == "BA_DEF_REL_" || kw == "BA_REL_" || kw == "BA_DEF_DEF_REL_" || kw == "BU_SG_REL_" ||
               kw == "BU_EV_REL_" || kw == "BU_BO_REL_" || kw == "CAT_DEF_" || kw == "CAT_" || kw == "FILTER" ||
               kw == "EV_DATA_" || kw == "SG_MUL_VAL_" || kw == "SIGTYPE_VALTYPE_") {
      if (kw == "SG_MUL_VAL_") error("extended multiplexing (SG_MUL_VAL_) is not supported; remove it", line);
      skip_statement();
    } else {
      error("unknown section keyword \"" + std::string(kw) + "\"; check the spelling or remove the line", line);
    }
  }
  db_.version = version_;
  fill_attribute_defaults();
  check_database();
  return std::move(db_);
}

void Parser::parse_ns() {
  expect(':', "after NS_");
  // The NS_ block lists keywords, one per line, up to BS_.
  while (true) {
    skip_ws();
    if (at_end()) error("NS_ block has no following BS_ section; add a line \"BS_:\"");
    const std::size_t save_pos = pos_;
    const int save_line = line_;
    const std::string_view word = identifier("a keyword in NS_");
    if (word == "BS_") {
      pos_ = save_pos;
      line_ = save_line;
      return;
    }
  }
}

void Parser::parse_bs() {
  expect(':', "after BS_");
  while (!at_line_end()) advance();  // optional baud rate and BTR values, unused
}

void Parser::parse_bu() {
  expect(':', "after BU_");
  while (!at_line_end()) {
    db_.nodes.emplace_back(identifier("a node name"));
  }
}

void Parser::parse_bo() {
  const int line = line_;
  const std::uint64_t raw_id = unsigned_number("the message id");
  const std::string name(identifier("the message name"));
  expect(':', "after the message name");
  const std::uint64_t dlc = unsigned_number("the message length");
  skip_blanks();
  std::string transmitter;
  if (!at_line_end()) transmitter = identifier("the transmitting node");
  if (!at_line_end()) error("unexpected text after the transmitter of " + name + describe_here());
  if (raw_id == kIndependentSignalsId) {
    current_ = &independent_sink_;
    independent_sink_ = MessageDef{};
    return;
  }
  if (raw_id > 0xFFFF'FFFFu) error("message id " + std::to_string(raw_id) + " of " + name + " is out of range", line);
  MessageDef m;
  m.name = name;
  m.extended = (raw_id & kDbcExtendedFlag) != 0;
  m.id = static_cast<std::uint32_t>(raw_id & 0x1FFF'FFFFu);
  if (!m.extended && m.id > 0x7FFu) {
    error("message " + name + " has standard id 0x" + hex(m.id) +
              " above 0x7FF; use an 11-bit id or mark it extended (add 0x80000000)",
          line);
  }
  if (dlc > 8) {
    error("message " + name + " is " + std::to_string(dlc) +
              " bytes long; classic CAN carries at most 8 (CAN FD is not supported)",
          line);
  }
  m.length = static_cast<std::uint8_t>(dlc);
  m.transmitter = transmitter == "Vector__XXX" ? "" : transmitter;
  m.line = line;
  for (const auto& other : db_.messages) {
    if (other.id == m.id && other.extended == m.extended) {
      error("message " + name + " reuses id 0x" + hex(m.id) + " of " + other.name + " (line " +
                std::to_string(other.line) + "); give each message its own id",
            line);
    }
    if (other.name == m.name) {
      error("message name " + name + " is used twice (also line " + std::to_string(other.line) +
                "); give each message its own name",
            line);
    }
  }
  db_.messages.push_back(std::move(m));
  current_ = &db_.messages.back();
}

void Parser::parse_sg() {
  const int line = line_;
  SignalDef s;
  s.line = line;
  s.name = identifier("the signal name");
  skip_blanks();
  if (peek() != ':') {
    const std::string_view mux = identifier("':' or a multiplexer indicator");
    error("signal " + s.name + " is multiplexed (" + std::string(mux) +
              "); multiplexed signals are not supported, give the message a fixed layout",
          line);
  }
  expect(':', "after the signal name");
  const std::uint64_t start = unsigned_number("the start bit");
  expect('|', "between start bit and length");
  const std::uint64_t length = unsigned_number("the signal length");
  expect('@', "before the byte order");
  skip_ws();
  const char order = peek();
  if (order != '0' && order != '1') {
    error("byte order of " + s.name + " must be 1 (Intel, little endian) or 0 (Motorola, big endian)" +
          describe_here());
  }
  advance();
  const char sign = peek();
  if (sign != '+' && sign != '-') {
    error("signal " + s.name + " needs '+' (unsigned) or '-' (signed) right after the byte order" + describe_here());
  }
  advance();
  expect('(', "before factor,offset");
  s.factor = number("the factor");
  expect(',', "between factor and offset");
  s.offset = number("the offset");
  expect(')', "after factor,offset");
  expect('[', "before minimum|maximum");
  s.minimum = number("the minimum");
  expect('|', "between minimum and maximum");
  s.maximum = number("the maximum");
  expect(']', "after minimum|maximum");
  s.unit = string_literal("the unit");
  while (!at_line_end()) {
    const std::string_view r = identifier("a receiving node");
    if (r != "Vector__XXX") s.receivers.emplace_back(r);
    skip_blanks();
    if (peek() == ',') advance();
  }
  if (length < 1 || length > 64) {
    error("signal " + s.name + " is " + std::to_string(length) + " bits long; use 1 to 64 bits", line);
  }
  if (start > 63) error("signal " + s.name + " starts at bit " + std::to_string(start) + "; use 0 to 63", line);
  s.start_bit = static_cast<std::uint16_t>(start);
  s.length = static_cast<std::uint16_t>(length);
  s.byte_order = order == '1' ? ByteOrder::kIntel : ByteOrder::kMotorola;
  s.value_type = sign == '-' ? ValueType::kSigned : ValueType::kUnsigned;
  if (s.factor == 0.0) error("signal " + s.name + " has factor 0; the factor must not be zero", line);
  if (s.minimum > s.maximum) {
    error("signal " + s.name + " has minimum above maximum; swap them", line);
  }
  for (const auto& other : current_->signals) {
    if (other.name == s.name) {
      error("signal " + s.name + " appears twice in " + current_->name + "; give each signal its own name", line);
    }
  }
  current_->signals.push_back(std::move(s));
}

void Parser::parse_cm() {
  skip_ws();
  const int line = line_;
  if (peek() == '"') {  // network comment
    string_literal("the comment");
  } else {
    const std::string_view what = identifier("BU_, BO_, SG_ or EV_");
    if (what == "BO_") {
      MessageDef* m = message_by_id(unsigned_number("the message id"), line);
      std::string text = string_literal("the comment");
      if (m != nullptr) m->comment = std::move(text);
    } else if (what == "SG_") {
      MessageDef* m = message_by_id(unsigned_number("the message id"), line);
      const std::string_view sig = identifier("the signal name");
      std::string text = string_literal("the comment");
      if (SignalDef* s = signal_in(m, sig, line)) s->comment = std::move(text);
    } else if (what == "BU_" || what == "EV_") {
      identifier("a name");
      string_literal("the comment");
    } else {
      error("CM_ must be followed by a string, BU_, BO_, SG_ or EV_", line);
    }
  }
  expect(';', "at the end of CM_");
}

std::string Parser::hex(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%X", v);
  return buf;
}

void Parser::parse_ba_def(bool is_default) {
  const int line = line_;
  if (is_default) {
    const std::string name = string_literal("the attribute name");
    AttributeDef* def = nullptr;
    for (auto& d : db_.attribute_defs) {
      if (d.name == name) def = &d;
    }
    if (def == nullptr) {
      error("BA_DEF_DEF_ for attribute \"" + name + "\" that no BA_DEF_ defines; define it first", line);
    }
    def->default_value = attribute_value(*def, line);
    expect(';', "at the end of BA_DEF_DEF_");
    return;
  }
  AttributeDef def;
  def.line = line;
  skip_ws();
  if (peek() != '"') {
    const std::string_view scope = identifier("BU_, BO_, SG_, EV_ or the attribute name");
    if (scope == "BU_") {
      def.scope = AttributeScope::kNode;
    } else if (scope == "BO_") {
      def.scope = AttributeScope::kMessage;
    } else if (scope == "SG_") {
      def.scope = AttributeScope::kSignal;
    } else if (scope == "EV_") {
      def.scope = AttributeScope::kEnvironment;
    } else {
      error("attribute scope must be BU_, BO_, SG_ or EV_ (or none), found \"" + std::string(scope) + "\"", line);
    }
  }
  def.name = string_literal("the attribute name");
  const std::string_view type = identifier("INT, HEX, FLOAT, STRING or ENUM");
  if (type == "INT" || type == "HEX" || type == "FLOAT") {
    def.type = type == "INT" ? AttributeType::kInt : type == "HEX" ? AttributeType::kHex : AttributeType::kFloat;
    skip_ws();
    if (peek() != ';') {
      def.minimum = number("the attribute minimum");
      def.maximum = number("the attribute maximum");
    }
  } else if (type == "STRING") {
    def.type = AttributeType::kString;
  } else if (type == "ENUM") {
    def.type = AttributeType::kEnum;
    skip_ws();
    while (peek() == '"') {
      def.enum_values.push_back(string_literal("an ENUM value"));
      if (!accept(',')) break;
      skip_ws();
    }
    if (def.enum_values.empty()) error("ENUM attribute \"" + def.name + "\" lists no values", line);
  } else {
    error("attribute type must be INT, HEX, FLOAT, STRING or ENUM, found \"" + std::string(type) + "\"", line);
  }
  expect(';', "at the end of BA_DEF_");
  for (const auto& d : db_.attribute_defs) {
    if (d.name == def.name) {
      error("attribute \"" + def.name + "\" is defined twice (also line " + std::to_string(d.line) + ")", line);
    }
  }
  db_.attribute_defs.push_back(std::move(def));
}

AttributeValue Parser::attribute_value(const AttributeDef& def, int line) {
  skip_ws();
  switch (def.type) {
    case AttributeType::kString:
      return string_literal("the attribute value");
    case AttributeType::kEnum: {
      if (peek() == '"') {
        const std::string v = string_literal("the attribute value");
        const auto it = std::find(def.enum_values.begin(), def.enum_values.end(), v);
        if (it == def.enum_values.end()) {
          std::string list;
          for (const auto& e : def.enum_values) list += (list.empty() ? "" : ", ") + e;
          error("\"" + v + "\" is not a value of attribute \"" + def.name + "\"; use one of: " + list, line);
        }
        return static_cast<std::int64_t>(it - def.enum_values.begin());
      }
      const std::int64_t index = integer("the ENUM index");
      if (index < 0 || static_cast<std::size_t>(index) >= def.enum_values.size()) {
        error("ENUM index " + std::to_string(index) + " of attribute \"" + def.name + "\" is out of range", line);
      }
      return index;
    }
    case AttributeType::kFloat: {
      const double v = number("the attribute value");
      if ((def.minimum != 0 || def.maximum != 0) && (v < def.minimum || v > def.maximum)) {
        error("value of attribute \"" + def.name + "\" is outside its range [" + bound_text(def.minimum) + ", " +
                  bound_text(def.maximum) + "]",
              line);
      }
      return v;
    }
    case AttributeType::kInt:
    case AttributeType::kHex: {
      const std::int64_t v = integer("the attribute value");
      if ((def.minimum != 0 || def.maximum != 0) &&
          (static_cast<double>(v) < def.minimum || static_cast<double>(v) > def.maximum)) {
        error("value " + std::to_string(v) + " of attribute \"" + def.name + "\" is outside its range [" +
                  bound_text(def.minimum) + ", " + bound_text(def.maximum) + "]",
              line);
      }
      return v;
    }
  }
  error("unreachable attribute type", line);
}

void Parser::parse_ba() {
  const int line = line_;
  const std::string name = string_literal("the attribute name");
  const AttributeDef* def = nullptr;
  for (const auto& d : db_.attribute_defs) {
    if (d.name == name) def = &d;
  }
  if (def == nullptr) error("attribute \"" + name + "\" is used but never defined; add a BA_DEF_ for it", line);
  skip_ws();
  std::map<std::string, AttributeValue>* target = &db_.network_attributes;
  AttributeScope scope = AttributeScope::kNetwork;
  if (is_ident_start(peek())) {
    const std::string_view what = identifier("BU_, BO_, SG_ or EV_");
    if (what == "BO_") {
      scope = AttributeScope::kMessage;
      MessageDef* m = message_by_id(unsigned_number("the message id"), line);
      target = m != nullptr ? &m->attributes : nullptr;
    } else if (what == "SG_") {
      scope = AttributeScope::kSignal;
      MessageDef* m = message_by_id(unsigned_number("the message id"), line);
      SignalDef* s = signal_in(m, identifier("the signal name"), line);
      target = s != nullptr ? &s->attributes : nullptr;
    } else if (what == "BU_" || what == "EV_") {
      scope = what == "BU_" ? AttributeScope::kNode : AttributeScope::kEnvironment;
      identifier("a name");
      target = nullptr;
    } else {
      error("BA_ object must be BU_, BO_, SG_ or EV_, found \"" + std::string(what) + "\"", line);
    }
  }
  if (scope != def->scope) {
    error("attribute \"" + name + "\" is defined for another kind of object (line " + std::to_string(def->line) +
              "); set it on the kind its BA_DEF_ names",
          line);
  }
  AttributeValue v = attribute_value(*def, line);
  expect(';', "at the end of BA_");
  if (target != nullptr) (*target)[name] = std::move(v);
}

void Parser::parse_val() {
  const int line = line_;
  skip_ws();
  if (is_ident_start(peek())) {  // value descriptions of an environment variable
    skip_statement();
    return;
  }
  MessageDef* m = message_by_id(unsigned_number("the message id"), line);
  SignalDef* s = signal_in(m, identifier("the signal name"), line);
  while (true) {
    skip_ws();
    if (peek() == ';') {
      advance();
      return;
    }
    const std::int64_t raw = integer("a raw value in VAL_");
    std::string text = string_literal("the value description");
    if (s != nullptr) s->value_names[raw] = std::move(text);
  }
}

void Parser::parse_sig_valtype() {
  const int line = line_;
  MessageDef* m = message_by_id(unsigned_number("the message id"), line);
  SignalDef* s = signal_in(m, identifier("the signal name"), line);
  expect(':', "in SIG_VALTYPE_");
  const std::uint64_t kind = unsigned_number("the value type (1 = float, 2 = double)");
  expect(';', "at the end of SIG_VALTYPE_");
  if (s == nullptr) return;
  if (kind == 1 || kind == 2) {
    const std::uint16_t want = kind == 1 ? 32 : 64;
    if (s->length != want) {
      error("signal " + s->name + " is declared " + (kind == 1 ? "float" : "double") + " but is " +
                std::to_string(s->length) + " bits long; make it " + std::to_string(want) + " bits",
            line);
    }
    s->value_type = kind == 1 ? ValueType::kFloat32 : ValueType::kFloat64;
  } else if (kind != 0) {
    error("SIG_VALTYPE_ must be 0 (integer), 1 (float) or 2 (double)", line);
  }
}

void Parser::parse_bo_tx_bu() {
  const int line = line_;
  MessageDef* m = message_by_id(unsigned_number("the message id"), line);
  expect(':', "in BO_TX_BU_");
  while (true) {
    skip_ws();
    if (peek() == ';') {
      advance();
      return;
    }
    if (peek() == ',') {
      advance();
      continue;
    }
    const std::string_view node = identifier("a transmitting node");
    if (m != nullptr) m->extra_transmitters.emplace_back(node);
  }
}

void Parser::fill_attribute_defaults() {
  for (const auto& def : db_.attribute_defs) {
    if (!def.default_value) continue;
    if (def.scope == AttributeScope::kMessage) {
      for (auto& m : db_.messages) m.attributes.try_emplace(def.name, *def.default_value);
    } else if (def.scope == AttributeScope::kSignal) {
      for (auto& m : db_.messages) {
        for (auto& s : m.signals) s.attributes.try_emplace(def.name, *def.default_value);
      }
    } else if (def.scope == AttributeScope::kNetwork) {
      db_.network_attributes.try_emplace(def.name, *def.default_value);
    }
  }
}

}  // namespace canhil::frames::dbc_detail
