// Where the page is, the token, loopback: the server's set-up.
#include <arpa/inet.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/base/setup_error.hpp"
#include "canhil/viewer/server.hpp"

namespace canhil::viewer {

std::string make_token() {
  std::ifstream random("/dev/urandom", std::ios::binary);
  unsigned char bytes[16] = {};
  if (!random.read(reinterpret_cast<char*>(bytes), sizeof bytes)) {
    throw SetupError("cannot read /dev/urandom for the viewer's token");
  }
  std::string hex;
  for (const unsigned char b : bytes) {
    char two[3];
    std::snprintf(two, sizeof two, "%02x", b);
    hex += two;
  }
  return hex;
}

bool is_loopback(const std::string& address) {
  if (address == "localhost" || address == "::1") return true;
  in_addr v4{};
  return inet_pton(AF_INET, address.c_str(), &v4) == 1 && (ntohl(v4.s_addr) >> 24) == 127;
}

std::filesystem::path default_web_root() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("CANHIL_VIEWER_ROOT"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    fs::path installed = exe.parent_path().parent_path() / "share" / "canhil" / "viewer";
    if (fs::is_regular_file(installed / "index.html", ec)) return installed;
  }
  return CANHIL_BUILD_VIEWER_ROOT;
}

}  // namespace canhil::viewer
