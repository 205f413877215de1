#include "canhil/viewer/page_client.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <strings.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <random>

namespace canhil::viewer {
namespace {

using Clock = std::chrono::steady_clock;

std::string errno_text(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

int connect_loopback(std::uint16_t port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw PageClientError(errno_text("socket"));
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const std::string text = errno_text(("connect to 127.0.0.1:" + std::to_string(port)).c_str());
    ::close(fd);
    throw PageClientError(text);
  }
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  return fd;
}

void write_all(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw PageClientError(errno_text("send"));
    done += static_cast<std::size_t>(n);
  }
}

// Some bytes, waiting until `deadline`; an empty string at the end of the stream.
std::string read_some(int fd, Clock::time_point deadline) {
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (left <= 0) throw PageClientError("no answer within the time limit");
    pollfd p{fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(left));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) throw PageClientError(errno_text("poll"));
    if (ready == 0) continue;
    std::array<char, 4096> buffer{};
    const ssize_t n = ::recv(fd, buffer.data(), buffer.size(), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw PageClientError(errno_text("recv"));
    return std::string(buffer.data(), static_cast<std::size_t>(n));
  }
}

// Reads an HTTP head (up to the blank line): the status code, the head, and what came after it.
struct Head {
  int status = 0;
  std::string text;
  std::string rest;
};

Head read_head(int fd, Clock::time_point deadline) {
  std::string got;
  std::size_t end = std::string::npos;
  while ((end = got.find("\r\n\r\n")) == std::string::npos) {
    const std::string more = read_some(fd, deadline);
    if (more.empty()) throw PageClientError("the server closed the connection before answering");
    got += more;
    if (got.size() > 65536) throw PageClientError("an HTTP head of more than 64 KiB");
  }
  Head h;
  h.text = got.substr(0, end);
  h.rest = got.substr(end + 4);
  if (h.text.compare(0, 5, "HTTP/") != 0 || h.text.size() < 12) throw PageClientError("not an HTTP answer: " + h.text);
  h.status = static_cast<int>(std::strtol(h.text.c_str() + h.text.find(' ') + 1, nullptr, 10));
  return h;
}

std::string base64(const std::array<unsigned char, 16>& bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::uint32_t second = i + 1 < bytes.size() ? std::uint32_t{bytes[i + 1]} : 0U;
    const std::uint32_t third = i + 2 < bytes.size() ? std::uint32_t{bytes[i + 2]} : 0U;
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) | (second << 8) | third;
    out += kDigits[(n >> 18) & 63];
    out += kDigits[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kDigits[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[n & 63] : '=';
  }
  return out;
}

std::mt19937& random_bytes() {
  static thread_local std::mt19937 r{std::random_device{}()};
  return r;
}

}  // namespace

PageClient::PageClient(std::uint16_t port, const std::string& target, const std::string& origin,
                       std::chrono::milliseconds timeout)
    : fd_(connect_loopback(port)) {
  try {
    std::array<unsigned char, 16> key{};
    for (unsigned char& b : key) b = static_cast<unsigned char>(random_bytes()() & 0xFF);
    std::string request = "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                          "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                          "Sec-WebSocket-Key: " +
                          base64(key) + "\r\n";
    if (!origin.empty()) request += "Origin: " + origin + "\r\n";
    write_all(fd_, request + "\r\n");
    Head h = read_head(fd_, Clock::now() + timeout);
    if (h.status != 101) throw PageClientError("the upgrade was refused: " + h.text.substr(0, h.text.find('\r')));
    pending_ = std::move(h.rest);
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

PageClient::~PageClient() {
  if (fd_ >= 0) ::close(fd_);
}

PageClient::PageClient(PageClient&& other) noexcept : fd_(other.fd_), pending_(std::move(other.pending_)) {
  other.fd_ = -1;
}

void PageClient::send_text(const std::string& text) { send_frame(0x1, text); }
void PageClient::send_binary(const std::string& bytes) { send_frame(0x2, bytes); }

void PageClient::send_frame(std::uint8_t opcode, const std::string& payload) {
  std::string frame;
  frame += static_cast<char>(0x80 | opcode);  // FIN, one frame
  const std::size_t n = payload.size();
  if (n < 126) {
    frame += static_cast<char>(0x80 | n);  // masked, as a client's frames must be
  } else if (n < 65536) {
    frame += static_cast<char>(0x80 | 126);
    frame += static_cast<char>((n >> 8) & 0xFF);
    frame += static_cast<char>(n & 0xFF);
  } else {
    frame += static_cast<char>(0x80 | 127);
    for (int shift = 56; shift >= 0; shift -= 8) frame += static_cast<char>((n >> shift) & 0xFF);
  }
  std::array<char, 4> mask{};
  for (char& m : mask) m = static_cast<char>(random_bytes()() & 0xFF);
  frame.append(mask.data(), mask.size());
  for (std::size_t i = 0; i < n; ++i) frame += static_cast<char>(payload[i] ^ mask[i % 4]);
  write_all(fd_, frame);
}

void PageClient::read_exact(char* out, std::size_t n, Clock::time_point deadline) {
  while (pending_.size() < n) {
    const std::string more = read_some(fd_, deadline);
    if (more.empty()) throw PageClientError("the server closed the connection");
    pending_ += more;
  }
  std::memcpy(out, pending_.data(), n);
  pending_.erase(0, n);
}

std::string PageClient::receive(std::chrono::milliseconds timeout) {
  const Clock::time_point deadline = Clock::now() + timeout;
  std::string message;
  for (;;) {
    std::array<unsigned char, 2> head{};
    read_exact(reinterpret_cast<char*>(head.data()), 2, deadline);
    const bool fin = (head[0] & 0x80) != 0;
    const int opcode = head[0] & 0x0F;
    std::uint64_t length = head[1] & 0x7F;
    if (length >= 126) {
      std::array<unsigned char, 8> ext{};
      const std::size_t bytes = length == 126 ? 2 : 8;
      read_exact(reinterpret_cast<char*>(ext.data()), bytes, deadline);
      length = 0;
      for (std::size_t i = 0; i < bytes; ++i) length = (length << 8) | ext[i];
    }
    if ((head[1] & 0x80) != 0) throw PageClientError("the server masked a frame");
    if (length > (64u << 20)) throw PageClientError("a frame of more than 64 MiB");
    std::string payload(static_cast<std::size_t>(length), '\0');
    if (length > 0) read_exact(payload.data(), payload.size(), deadline);
    if (opcode == 0x8) throw PageClientError("the server closed the connection");
    if (opcode == 0x9) {  // ping: answered, not a message
      send_frame(0xA, payload);
      continue;
    }
    if (opcode == 0xA) continue;
    message += payload;
    if (fin) return message;
  }
}

std::pair<int, std::string> http_get(std::uint16_t port, const std::string& target, std::chrono::milliseconds timeout) {
  const int fd = connect_loopback(port);
  const Clock::time_point deadline = Clock::now() + timeout;
  try {
    write_all(fd, "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    Head h = read_head(fd, deadline);
    std::string body = std::move(h.rest);
    std::size_t length = std::string::npos;
    for (std::size_t at = 0; (at = h.text.find("\r\n", at)) != std::string::npos; at += 2) {
      if (strncasecmp(h.text.c_str() + at + 2, "Content-Length:", 15) == 0) {
        length = std::strtoul(h.text.c_str() + at + 17, nullptr, 10);
      }
    }
    while (body.size() < length) {
      const std::string more = read_some(fd, deadline);
      if (more.empty()) break;
      body += more;
    }
    ::close(fd);
    if (length != std::string::npos && body.size() > length) body.resize(length);
    return {h.status, body};
  } catch (...) {
    ::close(fd);
    throw;
  }
}

}  // namespace canhil::viewer
