#include "run_view.hpp"

#include <thread>

#include "canhil/base/setup_error.hpp"
#include "commands.hpp"

namespace canhil::app {

ViewChoice view_options(Args& args) {
  ViewChoice c;
  const bool off = args.flag("--no-view");
  const auto port = optional_number(args, "--view-port");
  const auto listen = args.option("--view-listen");
  const auto hold = optional_number(args, "--view-hold");
  const auto dir = args.option("--save-dir");
  if (off && (port || listen || hold))
    throw UsageError("--no-view and --view-port/--view-listen/--view-hold: pick one");
  c.on = !off;
  if (port) {
    if (!(*port >= 0 && *port <= 65535 && *port == static_cast<int>(*port))) {
      throw UsageError("--view-port takes a port, 1..65535, or 0 for any free one");
    }
    c.port = static_cast<std::uint16_t>(*port);
  }
  if (listen) c.listen = *listen;
  if (hold) {
    if (!(*hold >= 0 && *hold <= 86400)) throw UsageError("--view-hold takes seconds, 0..86400");
    c.hold_s = *hold;
  }
  if (dir) {
    if (dir->empty()) throw UsageError("--save-dir takes a folder");
    c.save_dir = *dir;
  }
  return c;
}

std::unique_ptr<viewer::Server> start_viewer(const ViewChoice& choice, viewer::Feed& feed, const char* who, FILE* out,
                                             bool required) {
  if (!choice.on) return nullptr;
  viewer::ServerOptions o;
  o.listen = choice.listen;
  o.port = choice.port;
  o.web_root = viewer::default_web_root();
  if (!viewer::is_loopback(choice.listen)) o.token = viewer::make_token();
  try {
    auto server = std::make_unique<viewer::Server>(o, feed);
    std::fprintf(out, "%s: viewer at %s\n", who, server->url().c_str());
    if (!o.token.empty()) {
      std::fprintf(out, "%s: the viewer listens on %s: other machines open it with ?token=%s\n", who,
                   choice.listen.c_str(), o.token.c_str());
    }
    std::fflush(out);
    return server;
  } catch (const SetupError& e) {
    if (required) throw UsageError(e.what());
    std::fprintf(out, "%s: no viewer: %s\n", who, e.what());
    std::fflush(out);
    return nullptr;
  }
}

void hold_viewer(const ViewChoice& choice, const viewer::Server* server, const char* who, const std::atomic<bool>& stop,
                 FILE* out) {
  if (server == nullptr || choice.hold_s <= 0) return;
  std::fprintf(out, "%s: the viewer stays up %g s more at %s (Ctrl-C ends it)\n", who, choice.hold_s,
               server->url().c_str());
  std::fflush(out);
  serve_until(stop, choice.hold_s);
}

void serve_until(const std::atomic<bool>& stop, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!stop && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

}  // namespace canhil::app
