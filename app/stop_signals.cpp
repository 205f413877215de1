// app/stop_signals.cpp — stop_signals.hpp.
#include "stop_signals.hpp"

#include <csignal>
#include <cstdio>

namespace canhil::app {

std::atomic<bool> g_stop{false};

namespace {

static_assert(std::atomic<bool>::is_always_lock_free, "set from a signal handler");

volatile std::sig_atomic_t g_sigpipe = 0;

extern "C" void on_stop(int signal_number) {
  if (signal_number == SIGPIPE) g_sigpipe = 1;
  g_stop = true;
}

}  // namespace

void stop_on_signals() {
  std::signal(SIGINT, on_stop);
  std::signal(SIGTERM, on_stop);
  std::signal(SIGPIPE, on_stop);
}

void end_by_sigpipe_if_seen() {
  if (g_sigpipe == 0) return;
  std::fflush(nullptr);  // what the command printed before it ended, where a reader still takes it
  std::signal(SIGPIPE, SIG_DFL);
  sigset_t pipe_signal;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  sigprocmask(SIG_UNBLOCK, &pipe_signal, nullptr);
  std::raise(SIGPIPE);
}

}  // namespace canhil::app
