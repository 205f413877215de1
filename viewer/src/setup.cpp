// Where the page is, the token, loopback: the server's set-up.
#include <arpa/inet.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "canhil/base/assets.hpp"
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
  if (auto given = path_from_environment("CANHIL_VIEWER_ROOT")) return *given;
  return installed_or_built({"../share/canhil/viewer"}, CANHIL_BUILD_VIEWER_ROOT, [](const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p / "index.html", ec);
  });
}

}  // namespace canhil::viewer
