// canhil/base/xml_text.hpp — text put into an SVG (or any XML) element: the
// names, titles and labels of canhil's plots (`canhil timing --svg`,
// `canhil match --report --svg`), which come from the user's DBC and scenario,
// and text anywhere in an XML file (xml_escaped: `canhil test --junit`).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace canhil {

/// `text` with the three characters that end or start markup in element
/// content (<, >, &) written as entities; everything else as it is.
inline std::string xml_text(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else {
      out += c;
    }
  }
  return out;
}

namespace detail {
/// The length of the valid UTF-8 sequence at s[k], or 0.
inline std::size_t utf8_length(std::string_view s, std::size_t k) {
  const auto c = static_cast<unsigned char>(s[k]);
  std::size_t n = 0;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
  }
  if (n == 0 || k + n > s.size()) return 0;
  for (std::size_t i = 1; i < n; ++i) {
    if ((static_cast<unsigned char>(s[k + i]) & 0xC0) != 0x80) return 0;
  }
  return n;
}
}  // namespace detail

/// `text` for an attribute value or element content of any XML file (a
/// JUnit report's messages, which carry what a run measured and a team's
/// names): the five special characters as entities, and every character XML
/// 1.0 cannot carry (a control other than tab, newline and carriage return,
/// a byte that is not valid UTF-8) as '?', so that any text makes a
/// well-formed file.
inline std::string xml_escaped(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t k = 0; k < text.size(); ++k) {
    const char c = text[k];
    const auto u = static_cast<unsigned char>(c);
    if (c == '&') {
      out += "&amp;";
    } else if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '"') {
      out += "&quot;";
    } else if (c == '\'') {
      out += "&apos;";
    } else if (u < 0x20) {
      out += c == '\t' || c == '\n' || c == '\r' ? c : '?';
    } else if (u < 0x80) {
      out += c;
    } else if (const std::size_t n = detail::utf8_length(text, k); n > 0) {
      out.append(text.substr(k, n));
      k += n - 1;
    } else {
      out += '?';
    }
  }
  return out;
}

}  // namespace canhil
