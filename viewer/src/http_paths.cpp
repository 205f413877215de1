#include "http_paths.hpp"

#include <algorithm>
#include <cctype>

namespace canhil::viewer {
namespace {

int hex(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Percent-decoding; nullopt for a broken escape or a NUL.
std::optional<std::string> decoded(std::string_view s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '%') {
      if (i + 2 >= s.size()) return std::nullopt;
      const int hi = hex(s[i + 1]), lo = hex(s[i + 2]);
      if (hi < 0 || lo < 0) return std::nullopt;
      const char c = static_cast<char>(hi * 16 + lo);
      if (c == '\0') return std::nullopt;
      out += c;
      i += 2;
    } else if (s[i] == '+') {
      out += ' ';
    } else {
      out += s[i];
    }
  }
  return out;
}

}  // namespace

std::string path_of(std::string_view target) {
  const auto q = target.find('?');
  return decoded(target.substr(0, q)).value_or("");
}

std::string query_of(std::string_view target) {
  const auto q = target.find('?');
  return q == std::string_view::npos ? std::string() : std::string(target.substr(q + 1));
}

std::string query_value(std::string_view target, std::string_view key) {
  const std::string query = query_of(target);
  std::string_view rest = query;
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    const auto eq = pair.find('=');
    if (decoded(pair.substr(0, eq)).value_or("") == key) {
      return eq == std::string_view::npos ? std::string() : decoded(pair.substr(eq + 1)).value_or("");
    }
    if (amp == std::string_view::npos) break;
    rest = rest.substr(amp + 1);
  }
  return {};
}

WebFile file_under(const std::filesystem::path& root, const std::string& path) {
  const auto refused = [] { return WebFile{WebFile::Kind::kRefused, {}}; };
  if (path.empty() || path[0] != '/' || path.find('\\') != std::string::npos) return refused();
  std::filesystem::path rel;
  std::size_t start = 1;
  while (start <= path.size()) {
    const auto slash = path.find('/', start);
    const std::string part = path.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    if (!part.empty()) {
      if (part[0] == '.') return refused();  // "..", ".hidden"
      rel /= part;
    }
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  if (rel.empty() || path.back() == '/') rel /= "index.html";
  std::error_code ec;
  const auto full = std::filesystem::weakly_canonical(root / rel, ec);
  if (ec) return refused();
  // A symbolic link out of the root is refused as well.
  const auto [r, f] = std::mismatch(root.begin(), root.end(), full.begin(), full.end());
  if (r != root.end()) return refused();
  if (!std::filesystem::exists(full, ec)) return {WebFile::Kind::kMissing, {}};
  if (!std::filesystem::is_regular_file(full, ec)) return refused();
  return {WebFile::Kind::kFound, full};
}

std::string content_type(const std::filesystem::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".ico") return "image/x-icon";
  return "application/octet-stream";
}

bool same_origin(std::string_view origin, std::string_view host) {
  if (origin.empty()) return true;  // not a browser
  const auto scheme = origin.find("://");
  if (scheme == std::string_view::npos) return false;
  std::string o(origin.substr(scheme + 3)), h(host);
  for (auto* s : {&o, &h}) {
    for (char& c : *s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return !h.empty() && o == h;
}

}  // namespace canhil::viewer
