// app/run_view.hpp — the viewer of `canhil run` and `canhil view`: its
// options (--view-port, --view-listen, --no-view, --view-hold, --save-dir),
// starting the server (a port that is taken costs the viewer, not the run)
// and holding it up after a run.
#pragma once

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "args.hpp"
#include "canhil/viewer/server.hpp"

namespace canhil::app {

struct ViewChoice {
  bool on = true;
  std::string listen = "127.0.0.1";
  std::uint16_t port = 8765;
  double hold_s = 0;  ///< after the run, keep serving this long
  std::filesystem::path save_dir = "canhil-saves";
};

/// Takes the viewer's options from `args` (UsageError for bad values).
ViewChoice view_options(Args& args);

/// Starts the server and prints its address ("WHO: viewer at URL"); when it
/// cannot (a port taken), prints why and returns nullptr: the run goes on.
/// `required`: the viewer is the whole point (canhil view): a SetupError instead.
std::unique_ptr<viewer::Server> start_viewer(const ViewChoice& choice, viewer::Feed& feed, const char* who, FILE* out,
                                             bool required = false);

/// Waits until `stop` is set or `seconds` of wall time have passed (the viewer serves meanwhile).
void serve_until(const std::atomic<bool>& stop, double seconds);

/// After a run: keeps the viewer up for choice.hold_s (until `stop`), saying so.
void hold_viewer(const ViewChoice& choice, const viewer::Server* server, const char* who, const std::atomic<bool>& stop,
                 FILE* out);

}  // namespace canhil::app
