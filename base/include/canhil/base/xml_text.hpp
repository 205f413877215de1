// canhil/base/xml_text.hpp — text put into an SVG (or any XML) element: the
// names, titles and labels of canhil's plots (`canhil timing --svg`,
// `canhil match --report --svg`), which come from the user's DBC and scenario.
#pragma once

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

}  // namespace canhil
