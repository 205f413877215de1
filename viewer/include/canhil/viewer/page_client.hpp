// canhil/viewer/page_client.hpp — the viewer's protocol from the page's side,
// on a plain blocking socket: a WebSocket connection (RFC 6455: the upgrade,
// masked frames out, whole messages in) and a GET. For the benchmark that
// measures a connected page and for the server's tests, so that the server
// is checked against a second implementation of the protocol, not its own
// library's client. Loopback only (127.0.0.1); not for the page itself.
#pragma once

#include <chrono>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>

namespace canhil::viewer {

/// The server refused or broke the protocol, or a wait ran out; what() says which.
class PageClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One WebSocket connection to 127.0.0.1:port. Not thread-safe; movable only.
class PageClient {
 public:
  /// Connects and upgrades `target` ("/ws?token=..."), sending `origin` as
  /// the Origin header when not empty. Throws PageClientError when the
  /// connection or the upgrade is refused (the HTTP status in what()).
  PageClient(std::uint16_t port, const std::string& target, const std::string& origin = "",
             std::chrono::milliseconds timeout = std::chrono::seconds(5));
  ~PageClient();
  PageClient(PageClient&& other) noexcept;
  PageClient& operator=(PageClient&&) = delete;
  PageClient(const PageClient&) = delete;
  PageClient& operator=(const PageClient&) = delete;

  void send_text(const std::string& text);
  void send_binary(const std::string& bytes);
  /// The next whole message (text or binary; pings are answered, fragments
  /// joined). Throws PageClientError when none comes within `timeout` or the
  /// server closes the connection.
  std::string receive(std::chrono::milliseconds timeout = std::chrono::seconds(5));

 private:
  void send_frame(std::uint8_t opcode, const std::string& payload);
  void read_exact(char* out, std::size_t n, std::chrono::steady_clock::time_point deadline);
  int fd_ = -1;
  std::string pending_;  // bytes read past the upgrade's response
};

/// GET `target` from 127.0.0.1:port: the status code and the body.
std::pair<int, std::string> http_get(std::uint16_t port, const std::string& target,
                                     std::chrono::milliseconds timeout = std::chrono::seconds(5));

}  // namespace canhil::viewer
