// canhil/control/unix_server.hpp — the control socket of a running canhil:
// a Unix stream socket, one JSON request per line, one reply per line
// (canhil/control/commands.hpp). Owner-only (the socket 0600 in a 0700
// folder): what reaches it comes from the user who started the run.
//
// One thread serves one connection at a time; a line longer than
// kMaxRequestBytes is refused and the connection closed; an idle connection
// is closed after a few seconds. Never blocks the run: the commands only
// queue changes on the session.
#pragma once

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "canhil/control/commands.hpp"

namespace canhil::control {

/// Where a run's control socket is by default: $XDG_RUNTIME_DIR/canhil/control,
/// or /tmp/canhil-UID/control.
std::filesystem::path default_socket_path();

class UnixServer {
 public:
  /// Binds `path` (its folder made 0700 when missing) and starts serving.
  /// SetupError when another run already serves there (say which path to
  /// give instead) or the path cannot be bound. A socket left by a crashed
  /// run is replaced.
  UnixServer(std::filesystem::path path, Commands& commands);
  ~UnixServer();  // stops, joins, removes the socket
  UnixServer(const UnixServer&) = delete;
  UnixServer& operator=(const UnixServer&) = delete;

  const std::filesystem::path& path() const noexcept { return path_; }
  std::uint64_t requests() const noexcept { return requests_; }

 private:
  void serve();
  void serve_connection(int fd);

  std::filesystem::path path_;
  Commands& commands_;
  int listen_fd_ = -1;
  int wake_[2] = {-1, -1};  // a pipe that wakes the thread to stop
  std::atomic<std::uint64_t> requests_{0};
  std::thread thread_;
};

/// Sends one request to the control socket at `path` and returns the reply
/// line. SetupError when nothing serves there (is canhil run running?).
std::string send_request(const std::filesystem::path& path, const std::string& request_json);

}  // namespace canhil::control
