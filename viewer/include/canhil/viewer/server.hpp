// canhil/viewer/server.hpp — the viewer's web server: the page's files over
// HTTP and one WebSocket per page (/ws) on which the server streams the world
// and takes commands (docs/viewer.md is the protocol). Boost.Beast, one
// thread of its own: nothing here runs on, or waits for, the thread that
// steps the world. What is shown and done comes from a Feed (live_feed.hpp:
// a running session; replay_feed.hpp: a recorded run).
//
// Safety: files only from the web root (a path that leaves it is refused);
// listening beyond loopback needs the token printed at start (?token=...) for
// the WebSocket and /api; a WebSocket whose page came from another site
// (Origin not this server) is refused, so a web page elsewhere cannot drive a
// run; a slow page gets fewer states, never a growing queue.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include <nlohmann/json.hpp>

namespace canhil::viewer {

/// What the server shows and does: implemented by a live run and by a replay.
class Feed {
 public:
  virtual ~Feed() = default;
  /// The first message to a page (type "hello").
  virtual nlohmann::json hello() = 0;
  /// The state to stream now (type "state"), or null for nothing; called on
  /// the server's thread at most stream_hz times a second per page.
  virtual nlohmann::json state() = 0;
  /// A page's request (one WebSocket text message) -> the reply ({"ok": ...}).
  virtual nlohmann::json request(std::string_view text) = 0;
  /// GET /api/PATH?QUERY -> a JSON body, or nullopt for 404.
  virtual std::optional<std::string> api(std::string_view path, std::string_view query) {
    (void)path;
    (void)query;
    return std::nullopt;
  }
};

struct ServerOptions {
  std::string listen = "127.0.0.1";
  std::uint16_t port = 8765;  ///< 0: any free port (see Server::port())
  std::filesystem::path web_root;
  double stream_hz = 30;
  /// Needed on the WebSocket and /api as ?token=...: set for any address but
  /// loopback (make_token()); empty: none needed.
  std::string token;
};

/// 32 hex digits from the kernel's random source.
std::string make_token();
/// True for 127.0.0.0/8 and ::1 (and "localhost").
bool is_loopback(const std::string& address);
/// The folder of the page's files: $CANHIL_VIEWER_ROOT, the installed
/// share/canhil/viewer beside the binary, or the build tree's.
std::filesystem::path default_web_root();

class Server {
 public:
  /// Binds and starts serving. SetupError when the address cannot be bound
  /// (say which port is taken and what to give instead) or the web root has
  /// no index.html.
  Server(ServerOptions options, Feed& feed);
  ~Server();  // stops and joins
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  std::uint16_t port() const noexcept;
  /// The page's address (with the token when one is needed).
  std::string url() const;
  /// Sends {"type": "log", "text": ...} to every page (any thread).
  void log(const std::string& text);

  struct Counters {
    std::uint64_t pages = 0;         ///< WebSocket connections so far
    std::uint64_t states = 0;        ///< state messages sent
    std::uint64_t requests = 0;      ///< WebSocket messages taken
    std::uint64_t http_refused = 0;  ///< files outside the root, bad tokens, foreign origins, bad requests
  };
  Counters counters() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace canhil::viewer
