// viewer/src/http_paths.hpp — what the server makes of a request's target:
// its path and query, the file it names under the web root (or none, when it
// would leave the root), the content type, the origin check. Pure functions,
// tested on their own (tests/viewer/http_paths_test.cpp).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace canhil::viewer {

/// "/a/b?x=1" -> "/a/b" (percent-escapes decoded; nullopt-free: a bad escape gives "").
std::string path_of(std::string_view target);
/// "/a/b?x=1" -> "x=1"
std::string query_of(std::string_view target);
/// The value of `key` in the target's query ("" when absent).
std::string query_value(std::string_view target, std::string_view key);
/// What a request's path names under the web root.
struct WebFile {
  enum class Kind {
    kFound,    ///< `file` is a regular file under the root (canonical)
    kMissing,  ///< a well-formed path inside the root with no file there (404)
    kRefused,  ///< it would leave the root, names a hidden file or is malformed (403)
  };
  Kind kind = Kind::kRefused;
  std::filesystem::path file;
};
/// The file `path` ("/", "/lib/x.js") names under `root` (canonical). "/" and
/// a folder are their index.html.
WebFile file_under(const std::filesystem::path& root, const std::string& path);
std::string content_type(const std::filesystem::path& file);
/// A WebSocket's Origin header against the Host it was sent to: no origin
/// (not a browser) or the same host and port.
bool same_origin(std::string_view origin, std::string_view host);

}  // namespace canhil::viewer
