#include "canhil/control/unix_server.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "canhil/base/setup_error.hpp"

namespace canhil::control {
namespace {

constexpr int kIdleMs = 5000;  // a connection that sends nothing this long is closed

sockaddr_un address_of(const std::filesystem::path& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  const std::string p = path.string();
  if (p.size() >= sizeof a.sun_path) {
    throw SetupError("the control socket path " + p + " is too long (at most " + std::to_string(sizeof a.sun_path - 1) +
                     " characters); give a shorter --control");
  }
  std::memcpy(a.sun_path, p.c_str(), p.size() + 1);
  return a;
}

bool something_serves(const std::filesystem::path& path) {
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const sockaddr_un a = address_of(path);
  const bool yes = connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  ::close(fd);
  return yes;
}

bool write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::send(fd, text.data(), text.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

}  // namespace

std::filesystem::path default_socket_path() {
  if (const char* run = std::getenv("XDG_RUNTIME_DIR"); run != nullptr && *run != '\0') {
    return std::filesystem::path(run) / "canhil" / "control";
  }
  return std::filesystem::path("/tmp") / ("canhil-" + std::to_string(getuid())) / "control";
}

UnixServer::UnixServer(std::filesystem::path path, Commands& commands) : path_(std::move(path)), commands_(commands) {
  const std::filesystem::path folder = path_.parent_path();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::exists(folder, ec)) {
    std::filesystem::create_directories(folder, ec);
    if (ec || chmod(folder.c_str(), 0700) != 0) {
      throw SetupError("cannot make the folder " + folder.string() + " for the control socket: " + ec.message());
    }
  }
  if (std::filesystem::exists(path_, ec)) {
    if (something_serves(path_)) {
      throw SetupError("another canhil run serves " + path_.string() +
                       "; stop it, or give this run its own socket with --control PATH");
    }
    std::filesystem::remove(path_, ec);  // left by a crashed run
  }
  listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const sockaddr_un a = address_of(path_);
  const mode_t old = umask(0177);  // the socket is born 0600
  const bool bound = listen_fd_ >= 0 && bind(listen_fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0 &&
                     listen(listen_fd_, 8) == 0;
  umask(old);
  if (!bound || pipe2(wake_, O_CLOEXEC) != 0) {
    const std::string why = std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    throw SetupError("cannot serve the control socket " + path_.string() + ": " + why);
  }
  thread_ = std::thread([this] { serve(); });
}

UnixServer::~UnixServer() {
  [[maybe_unused]] const auto n = ::write(wake_[1], "x", 1);
  if (thread_.joinable()) thread_.join();
  ::close(listen_fd_);
  ::close(wake_[0]);
  ::close(wake_[1]);
  std::error_code ec;
  std::filesystem::remove(path_, ec);
}

void UnixServer::serve() {
  while (true) {
    pollfd p[2] = {{listen_fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(p, 2, -1) < 0 && errno != EINTR) return;
    if ((p[1].revents & POLLIN) != 0) return;
    if ((p[0].revents & POLLIN) == 0) continue;
    const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    serve_connection(fd);
    ::close(fd);
  }
}

void UnixServer::serve_connection(int fd) {
  std::string buffer;
  char chunk[4096];
  while (true) {
    pollfd p[2] = {{fd, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(p, 2, kIdleMs) <= 0 || (p[1].revents & POLLIN) != 0) return;
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) return;
    buffer.append(chunk, static_cast<std::size_t>(n));
    for (auto eol = buffer.find('\n'); eol != std::string::npos; eol = buffer.find('\n')) {
      const std::string line = buffer.substr(0, eol);
      buffer.erase(0, eol + 1);
      ++requests_;
      if (!write_all(fd, commands_.handle(line) + "\n")) return;
    }
    if (buffer.size() > kMaxRequestBytes) {
      write_all(fd, commands_.handle(std::string_view(buffer)) + "\n");  // refused as too long
      return;
    }
  }
}

std::string send_request(const std::filesystem::path& path, const std::string& request_json) {
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const sockaddr_un a = address_of(path);
  if (fd < 0 || connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    if (fd >= 0) ::close(fd);
    throw SetupError("nothing serves the control socket " + path.string() +
                     ": is canhil run running (its first lines name its socket)? Give it with --control PATH");
  }
  std::string reply;
  if (write_all(fd, request_json + "\n")) {
    char chunk[4096];
    while (reply.find('\n') == std::string::npos) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, kIdleMs) <= 0) break;
      const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
      if (n <= 0) break;
      reply.append(chunk, static_cast<std::size_t>(n));
    }
  }
  ::close(fd);
  if (reply.empty()) throw SetupError("the run at " + path.string() + " did not answer");
  return reply.substr(0, reply.find('\n'));
}

}  // namespace canhil::control
