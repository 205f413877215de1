// app/stop_signals.cpp — stop_signals.hpp.
#include "stop_signals.hpp"

#include <atomic>
#include <csignal>

namespace canhil::app {
namespace {

std::atomic<void (*)(int)> g_stop{nullptr};
volatile std::sig_atomic_t g_sigpipe = 0;

extern "C" void on_sigpipe(int signal_number) {
  g_sigpipe = 1;
  if (auto* stop = g_stop.load()) stop(signal_number);
}

}  // namespace

void stop_on_signals(void (*stop)(int)) {
  static_assert(std::atomic<void (*)(int)>::is_always_lock_free, "read from a signal handler");
  g_stop = stop;
  std::signal(SIGINT, stop);
  std::signal(SIGTERM, stop);
  std::signal(SIGPIPE, on_sigpipe);
}

void end_by_sigpipe_if_seen() {
  if (g_sigpipe == 0) return;
  std::signal(SIGPIPE, SIG_DFL);
  std::raise(SIGPIPE);
}

}  // namespace canhil::app
