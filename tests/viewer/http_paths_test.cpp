// What the server makes of a request's target: nothing outside the page's folder.
#include "http_paths.hpp"
#include "canhil/viewer/server.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>

namespace canhil::viewer {
namespace {

TEST(HttpPaths, PathAndQueryAreSplitAndDecoded) {
  EXPECT_EQ(path_of("/a/b%20c?x=1"), "/a/b c");
  EXPECT_EQ(query_of("/a?x=1&y=2"), "x=1&y=2");
  EXPECT_EQ(query_value("/ws?token=ab%2Fc&x=1", "token"), "ab/c");
  EXPECT_EQ(query_value("/ws?x=1", "token"), "");
  EXPECT_EQ(path_of("/a%2"), "");  // a broken escape names nothing
  EXPECT_EQ(path_of("/a%00b"), "");
}

TEST(HttpPaths, OnlyFilesUnderTheRoot) {
  const auto root = std::filesystem::temp_directory_path() / ("canhil-paths-" + std::to_string(getpid()));
  std::filesystem::create_directories(root / "web" / "lib");
  std::ofstream(root / "web" / "index.html") << "i";
  std::ofstream(root / "web" / "lib" / "a.js") << "a";
  std::ofstream(root / "outside") << "o";
  const auto web = std::filesystem::canonical(root / "web");
  using Kind = WebFile::Kind;
  EXPECT_EQ(file_under(web, "/").file, web / "index.html");
  EXPECT_EQ(file_under(web, "/lib/a.js").file, web / "lib" / "a.js");
  EXPECT_EQ(file_under(web, "//lib//a.js").file, web / "lib" / "a.js");
  EXPECT_EQ(file_under(web, "/lib/a.js").kind, Kind::kFound);
  EXPECT_EQ(file_under(web, "/../outside").kind, Kind::kRefused);
  EXPECT_EQ(file_under(web, "/lib/../../outside").kind, Kind::kRefused);
  EXPECT_EQ(file_under(web, "/lib/./a.js").kind, Kind::kRefused);
  EXPECT_EQ(file_under(web, "/lib\\..\\..\\outside").kind, Kind::kRefused);
  EXPECT_EQ(file_under(web, "relative").kind, Kind::kRefused);
  EXPECT_EQ(file_under(web, "/lib/").kind, Kind::kMissing);  // a folder without an index
  EXPECT_EQ(file_under(web, "/missing.js").kind, Kind::kMissing);
  EXPECT_EQ(file_under(web, "/lib/missing/deeper.js").kind, Kind::kMissing);
  EXPECT_TRUE(file_under(web, "/missing.js").file.empty());
  std::filesystem::remove_all(root);
}

TEST(HttpPaths, ContentTypesAndOrigins) {
  EXPECT_EQ(content_type("a.js"), "text/javascript; charset=utf-8");
  EXPECT_EQ(content_type("a.css"), "text/css; charset=utf-8");
  EXPECT_EQ(content_type("a.bin"), "application/octet-stream");
  EXPECT_TRUE(same_origin("", "127.0.0.1:8765"));
  EXPECT_TRUE(same_origin("http://127.0.0.1:8765", "127.0.0.1:8765"));
  EXPECT_TRUE(same_origin("http://LOCALHOST:8765", "localhost:8765"));
  EXPECT_FALSE(same_origin("http://evil.example", "127.0.0.1:8765"));
  EXPECT_FALSE(same_origin("http://127.0.0.1:9999", "127.0.0.1:8765"));
  EXPECT_FALSE(same_origin("null", "127.0.0.1:8765"));
}

TEST(HttpPaths, LoopbackAndTokens) {
  EXPECT_TRUE(is_loopback("127.0.0.1"));
  EXPECT_TRUE(is_loopback("127.1.2.3"));
  EXPECT_TRUE(is_loopback("::1"));
  EXPECT_FALSE(is_loopback("0.0.0.0"));
  EXPECT_FALSE(is_loopback("192.168.1.5"));
  const std::string a = make_token(), b = make_token();
  EXPECT_EQ(a.size(), 32u);
  EXPECT_NE(a, b);
}

}  // namespace
}  // namespace canhil::viewer
