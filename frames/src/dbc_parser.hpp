// frames/src/dbc_parser.hpp — the DBC reader's parser, private to frames:
// a character cursor over the whole text that knows its line, recursive
// descent on top of it (dbc_parser.cpp: the sections; dbc_checks.cpp: the
// checks of the whole database once read). dbc.cpp is the public side.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <type_traits>

#include "canhil/frames/dbc.hpp"

namespace canhil::frames::dbc_detail {

// An attribute's bound as written in a message: whole numbers without a
// fraction, any magnitude (a DBC's numbers are user input: no cast to an
// integer type that might not hold them).
inline std::string bound_text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, std::fabs(v) < 1e15 && v == std::trunc(v) ? "%.0f" : "%g", v);
  return buf;
}

constexpr std::uint32_t kDbcExtendedFlag = 0x8000'0000u;
// Vector tools park signals that belong to no message in this pseudo-message.
constexpr std::uint32_t kIndependentSignalsId = 0xC000'0000u;

inline bool is_ident_start(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
inline bool is_ident_char(char c) { return is_ident_start(c) || (c >= '0' && c <= '9'); }

// A character cursor over the whole text that knows its line. Recursive descent
// on top of it; DBC is line-structured for BO_/SG_/BU_ and ';'-terminated for
// the rest, and both are handled here.
class Parser {
 public:
  Parser(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}

  Database parse();

 private:
  [[noreturn]] void error(const std::string& message, int line = -1) const {
    throw DbcError(file_, line < 0 ? line_ : line, message);
  }

  bool at_end() const { return pos_ >= text_.size(); }
  char peek() const { return at_end() ? '\0' : text_[pos_]; }
  void advance() {
    if (text_[pos_] == '\n') ++line_;
    ++pos_;
  }
  void skip_ws() {
    while (!at_end()) {
      const char c = peek();
      if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
        advance();
      } else if (c == '/' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '/') {
        while (!at_end() && peek() != '\n') advance();
      } else {
        break;
      }
    }
  }
  void skip_blanks() {  // within the line
    while (!at_end() && (peek() == ' ' || peek() == '\t' || peek() == '\r')) advance();
  }
  bool at_line_end() {
    skip_blanks();
    return at_end() || peek() == '\n';
  }

  std::string_view identifier(const char* what) {
    skip_ws();
    if (!is_ident_start(peek())) error(std::string("expected ") + what + describe_here());
    const std::size_t start = pos_;
    while (!at_end() && is_ident_char(peek())) advance();
    return text_.substr(start, pos_ - start);
  }
  std::string describe_here() const {
    if (at_end()) return ", found the end of the file";
    std::size_t end = pos_;
    while (end < text_.size() && end - pos_ < 20 && text_[end] != '\n' && text_[end] != '\r') ++end;
    return ", found \"" + std::string(text_.substr(pos_, end - pos_)) + "\"";
  }
  void expect(char c, const char* context) {
    skip_ws();
    if (peek() != c) error(std::string("expected '") + c + "' " + context + describe_here());
    advance();
  }
  bool accept(char c) {
    skip_ws();
    if (peek() != c) return false;
    advance();
    return true;
  }
  std::string_view number_text() {
    skip_ws();
    const std::size_t start = pos_;
    if (peek() == '-' || peek() == '+') advance();
    while (!at_end()) {
      const char c = peek();
      if ((c >= '0' && c <= '9') || c == '.' || c == 'e' || c == 'E' || c == 'x' || c == 'X' ||
          (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F') ||
          ((c == '-' || c == '+') && (text_[pos_ - 1] == 'e' || text_[pos_ - 1] == 'E'))) {
        advance();
      } else {
        break;
      }
    }
    return text_.substr(start, pos_ - start);
  }
  double number(const char* what) {
    const int line = line_;
    std::string_view t = number_text();
    if (!t.empty() && t.front() == '+') t.remove_prefix(1);
    double v = 0;
    const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || p != t.data() + t.size() || !std::isfinite(v)) {
      error(std::string("expected a number for ") + what +
                (t.empty() ? describe_here() : ", found \"" + std::string(t) + "\""),
            line);
    }
    return v;
  }
  std::uint64_t unsigned_number(const char* what) { return whole_number<std::uint64_t>(what); }
  std::int64_t integer(const char* what) { return whole_number<std::int64_t>(what); }
  // A whole number of type T (a signed one may carry a '+').
  template <class T>
  T whole_number(const char* what) {
    const int line = line_;
    std::string_view t = number_text();
    if (std::is_signed_v<T> && !t.empty() && t.front() == '+') t.remove_prefix(1);
    T v = 0;
    const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (t.empty() || ec != std::errc() || p != t.data() + t.size()) {
      error(std::string("expected a whole number for ") + what +
                (t.empty() ? describe_here() : ", found \"" + std::string(t) + "\""),
            line);
    }
    return v;
  }
  std::string string_literal(const char* what) {
    skip_ws();
    if (peek() != '"') error(std::string("expected a quoted string for ") + what + describe_here());
    const int start_line = line_;
    advance();
    std::string out;
    while (true) {
      if (at_end()) error("string opened here is never closed; add the closing '\"'", start_line);
      const char c = peek();
      if (c == '\\' && pos_ + 1 < text_.size()) {
        advance();
        out.push_back(peek());
        advance();
        continue;
      }
      advance();
      if (c == '"') break;
      out.push_back(c);
    }
    return out;
  }
  void skip_statement() {  // to the next ';' outside strings
    while (true) {
      skip_ws();
      if (at_end()) error("statement is never closed; add the ';' at its end");
      if (peek() == '"') {
        string_literal("text");
      } else if (peek() == ';') {
        advance();
        return;
      } else {
        advance();
      }
    }
  }

  void parse_version() { version_ = string_literal("VERSION"); }
  void parse_ns();
  void parse_bs();
  void parse_bu();
  void parse_bo();
  void parse_sg();
  void parse_cm();
  void parse_ba_def(bool is_default);
  void parse_ba();
  void parse_val();
  void parse_sig_valtype();
  void parse_bo_tx_bu();

  MessageDef* message_by_id(std::uint64_t raw_id, int line) {
    if (raw_id == kIndependentSignalsId) return nullptr;
    const bool ext = (raw_id & kDbcExtendedFlag) != 0;
    const auto id = static_cast<std::uint32_t>(raw_id & 0x1FFF'FFFFu);
    for (auto& m : db_.messages) {
      if (m.id == id && m.extended == ext) return &m;
    }
    error("no message with id " + std::to_string(raw_id) + " (BO_ " + std::to_string(raw_id) +
              ") is defined; define the message first or fix the id",
          line);
  }
  SignalDef* signal_in(MessageDef* m, std::string_view name, int line) {
    if (m == nullptr) return nullptr;
    for (auto& s : m->signals) {
      if (s.name == name) return &s;
    }
    error("message " + m->name + " has no signal " + std::string(name) + "; fix the name or add the signal", line);
  }
  AttributeValue attribute_value(const AttributeDef& def, int line);
  void check_database();
  void check_message(const MessageDef& m);
  void check_range(const MessageDef& m, const SignalDef& s);
  void fill_attribute_defaults();

  std::string_view text_;
  std::string file_;
  std::size_t pos_ = 0;
  int line_ = 1;
  std::string version_;
  Database db_;
  MessageDef* current_ = nullptr;
  MessageDef independent_sink_;  // signals of VECTOR__INDEPENDENT_SIG_MSG land here and are dropped
  static std::string hex(std::uint32_t v);
};

}  // namespace canhil::frames::dbc_detail
