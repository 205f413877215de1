#include "canhil/viewer/server.hpp"

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

#include "canhil/base/setup_error.hpp"
#include "http_paths.hpp"

namespace canhil::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using nlohmann::json;

constexpr std::size_t kMaxHttpBody = std::size_t{64} * 1024;
constexpr std::size_t kMaxWsMessage =
    std::size_t{1024} * 1024;            // the commands refuse anything over 64 KiB with a reply
constexpr std::size_t kMaxQueued = 256;  // replies and logs waiting for a page that reads nothing
constexpr auto kHttpTimeout = std::chrono::seconds(30);

std::string dumped(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

}  // namespace

struct Server::Impl {
  ServerOptions options;
  Feed& feed;
  net::io_context io{1};
  tcp::acceptor acceptor{io};
  std::thread thread;
  std::uint16_t port = 0;
  std::atomic<std::uint64_t> pages{0}, states{0}, requests{0}, http_refused{0};

  class WsSession;
  std::mutex sessions_mutex;  // the list; sessions themselves live on the io thread
  std::vector<std::weak_ptr<WsSession>> sessions;

  Impl(ServerOptions o, Feed& f) : options(std::move(o)), feed(f) {}
  void accept();
  bool token_ok(std::string_view target) const {
    return options.token.empty() || query_value(target, "token") == options.token;
  }
};

// One page's WebSocket: the hello, then states on a timer, replies to its requests.
class Server::Impl::WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(Impl& server, tcp::socket socket) : server_(server), ws_(std::move(socket)), timer_(ws_.get_executor()) {}

  void start(const http::request<http::string_body>& upgrade) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxWsMessage);
    ws_.async_accept(upgrade, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->queue(dumped(self->hello()));
      self->read();
      self->tick();
    });
  }

  void send_log(const std::string& text) { queue(dumped(json{{"type", "log"}, {"text", text}})); }

 private:
  json hello() {
    json h = server_.feed.hello();
    h["type"] = "hello";
    return h;
  }

  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();
      ++self->server_.requests;
      json reply;
      if (!self->ws_.got_text()) {
        reply = {{"ok", false}, {"error", "send requests as JSON text messages"}};
      } else {
        reply = self->server_.feed.request(beast::buffers_to_string(self->in_.data()));
      }
      self->in_.consume(self->in_.size());
      reply["type"] = "reply";
      self->queue(dumped(reply));
      self->read();
    });
  }

  void tick() {
    timer_.expires_after(std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::duration<double>(1.0 / server_.options.stream_hz)));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || self->closed_) return;
      // Only when the page has taken everything: a slow page gets fewer states, never a queue.
      if (!self->writing_ && self->out_.empty()) {
        json s = self->server_.feed.state();
        if (!s.is_null()) {
          s["type"] = "state";
          ++self->server_.states;
          self->queue(dumped(s));
        }
      }
      self->tick();
    });
  }

  void queue(std::string text) {
    if (closed_) return;
    if (out_.size() >= kMaxQueued) return close();  // a page that reads nothing is let go
    out_.push_back(std::move(text));
    if (!writing_) write();
  }

  void write() {
    writing_ = true;
    ws_.text(true);
    ws_.async_write(net::buffer(out_.front()), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (ec) return self->close();
      self->out_.pop_front();
      if (!self->out_.empty()) self->write();
    });
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    timer_.cancel();
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
  }

  Impl& server_;
  websocket::stream<beast::tcp_stream> ws_;
  net::steady_timer timer_;
  beast::flat_buffer in_;
  std::deque<std::string> out_;
  bool writing_ = false;
  bool closed_ = false;
};

namespace {

// One HTTP connection: files, /api, or the upgrade to the WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(Server::Impl& server, tcp::socket socket) : server_(server), stream_(std::move(socket)) {}

  void read() {
    parser_.emplace();
    parser_->body_limit(kMaxHttpBody);
    stream_.expires_after(kHttpTimeout);
    http::async_read(stream_, buffer_, *parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();
      self->handle(self->parser_->release());
    });
  }

 private:
  void handle(const http::request<http::string_body>& req) {
    const std::string target(req.target());
    if (websocket::is_upgrade(req)) {
      if (path_of(target) != "/ws") return respond(error(req, http::status::not_found, "the WebSocket is /ws"));
      if (!server_.token_ok(target)) {
        return respond(error(req, http::status::forbidden, "give the token printed at start: /ws?token=..."));
      }
      const auto origin = req[http::field::origin];
      const auto host = req[http::field::host];
      if (!same_origin(std::string_view(origin.data(), origin.size()), std::string_view(host.data(), host.size()))) {
        return respond(error(req, http::status::forbidden, "a page from another site may not drive this run"));
      }
      ++server_.pages;
      auto ws = std::make_shared<Server::Impl::WsSession>(server_, stream_.release_socket());
      {
        const std::lock_guard lock(server_.sessions_mutex);
        std::erase_if(server_.sessions, [](const auto& w) { return w.expired(); });
        server_.sessions.push_back(ws);
      }
      ws->start(req);
      return;
    }
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      return respond(error(req, http::status::method_not_allowed, "only GET"));
    }
    const std::string path = path_of(target);
    if (path.rfind("/api/", 0) == 0) {
      if (!server_.token_ok(target)) return respond(error(req, http::status::forbidden, "give the token: ?token=..."));
      const auto body = server_.feed.api(std::string_view(path).substr(5), query_of(target));
      if (!body) return respond(error(req, http::status::not_found, "no such data"));
      return respond(reply(req, http::status::ok, "application/json", *body));
    }
    const WebFile file = file_under(server_.options.web_root, path);
    if (file.kind == WebFile::Kind::kMissing) return respond(error(req, http::status::not_found, "no such file"));
    if (file.kind != WebFile::Kind::kFound) {
      return respond(error(req, http::status::forbidden, "not a file of the viewer"));
    }
    std::ifstream in(file.file, std::ios::binary);
    if (!in) return respond(error(req, http::status::not_found, "no such file"));
    std::ostringstream body;
    body << in.rdbuf();
    respond(reply(req, http::status::ok, content_type(file.file), body.str()));
  }

  static http::response<http::string_body> reply(const http::request<http::string_body>& req, http::status status,
                                                 std::string_view type, std::string body) {
    http::response<http::string_body> res{status, req.version()};
    res.set(http::field::server, "canhil");
    res.set(http::field::content_type, std::string(type));
    res.set(http::field::cache_control, "no-store");
    res.set("X-Content-Type-Options", "nosniff");
    res.keep_alive(req.keep_alive());
    if (req.method() != http::verb::head) res.body() = std::move(body);
    res.prepare_payload();
    return res;
  }

  http::response<http::string_body> error(const http::request<http::string_body>& req, http::status status,
                                          const std::string& why) {
    ++server_.http_refused;
    return reply(req, status, "text/plain; charset=utf-8", why + "\n");
  }

  void respond(http::response<http::string_body> res) {
    auto shared = std::make_shared<http::response<http::string_body>>(std::move(res));
    http::async_write(stream_, *shared, [self = shared_from_this(), shared](beast::error_code ec, std::size_t) {
      if (ec || !shared->keep_alive()) return self->close();
      self->read();
    });
  }

  void close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
  }

  Server::Impl& server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

void Server::Impl::accept() {
  acceptor.async_accept(io, [this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted) return;
    if (!ec) std::make_shared<HttpSession>(*this, std::move(socket))->read();
    accept();
  });
}

Server::Server(ServerOptions options, Feed& feed) : impl_(std::make_unique<Impl>(std::move(options), feed)) {
  Impl& s = *impl_;
  if (!(s.options.stream_hz > 0 && s.options.stream_hz <= 240)) throw SetupError("the stream rate is 0..240 Hz");
  std::error_code fec;
  if (!std::filesystem::is_regular_file(s.options.web_root / "index.html", fec)) {
    throw SetupError("the viewer's page is not in " + s.options.web_root.string() +
                     " (no index.html); set CANHIL_VIEWER_ROOT to its folder, or give --no-view");
  }
  s.options.web_root = std::filesystem::canonical(s.options.web_root);
  beast::error_code ec;
  const auto address = net::ip::make_address(s.options.listen == "localhost" ? "127.0.0.1" : s.options.listen, ec);
  if (ec) throw SetupError("--view-listen " + s.options.listen + " is not an IP address (e.g. 127.0.0.1 or 0.0.0.0)");
  const tcp::endpoint at{address, s.options.port};
  s.acceptor.open(at.protocol(), ec);
  if (!ec) s.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) s.acceptor.bind(at, ec);
  if (!ec) s.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    throw SetupError("the viewer cannot listen on " + s.options.listen + ":" + std::to_string(s.options.port) + " (" +
                     ec.message() + "); give another --view-port (0 takes a free one) or --no-view");
  }
  s.port = s.acceptor.local_endpoint().port();
  s.accept();
  s.thread = std::thread([&s] { s.io.run(); });
}

Server::~Server() {
  impl_->io.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::uint16_t Server::port() const noexcept { return impl_->port; }

std::string Server::url() const {
  const std::string host =
      impl_->options.listen == "0.0.0.0" || impl_->options.listen == "::" ? "127.0.0.1" : impl_->options.listen;
  const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host;
  std::string u = "http://" + shown + ":" + std::to_string(impl_->port) + "/";
  if (!impl_->options.token.empty()) u += "?token=" + impl_->options.token;
  return u;
}

void Server::log(const std::string& text) {
  net::post(impl_->io, [this, text] {
    std::vector<std::shared_ptr<Impl::WsSession>> live;
    {
      const std::lock_guard lock(impl_->sessions_mutex);
      for (const auto& w : impl_->sessions) {
        if (auto s = w.lock()) live.push_back(std::move(s));
      }
    }
    for (const auto& s : live) s->send_log(text);
  });
}

Server::Counters Server::counters() const {
  return Counters{impl_->pages, impl_->states, impl_->requests, impl_->http_refused};
}

}  // namespace canhil::viewer
