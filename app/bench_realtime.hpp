// app/bench_realtime.hpp — the real-time figures of `canhil bench`, measured
// on a live SocketCAN interface by a listening socket (kernel receive
// timestamps): release jitter of the emulator's trigger messages against a
// bare clock_nanosleep loop sending a frame on the same period, and the
// highest lossless frame rate through the interface against can-utils'
// `cangen -g 0`.
#pragma once

#include <cstdint>
#include <string>

#include "canhil/emulator/realtime_driver.hpp"
#include "canhil/emulator/scenario.hpp"

namespace canhil::app {

/// Lateness of periodic releases against their best-aligned schedule
/// (t_k - k * period, less the smallest such offset): their jitter.
struct JitterFigures {
  std::size_t releases = 0;   ///< frames measured (after the warm-up)
  std::uint64_t missing = 0;  ///< periods with no frame
  double p50_us = 0, p99_us = 0, max_us = 0;
};

/// A bare loop: clock_nanosleep to each absolute deadline, one frame sent; at
/// SCHED_FIFO `priority` (0: normal scheduler), as canhil run's node loop.
JitterFigures bare_loop_jitter(const std::string& iface, double seconds, std::chrono::nanoseconds period, int priority);
/// `canhil run` of the scenario (its first robot alone, on `iface`, everything on), its TMs.
JitterFigures emulator_jitter(const std::string& iface, double seconds, const emulator::Scenario& scenario,
                              const emulator::SessionOptions& session, const emulator::RealtimeOptions& options);

struct RateFigures {
  std::uint64_t sent = 0;      ///< frames the sender handed to the kernel
  std::uint64_t received = 0;  ///< by the listening socket
  std::uint64_t lost = 0;      ///< sender drops + receive overflow + gaps
  double frames_per_s = 0;     ///< received / (last - first kernel timestamp)
};

/// canhil's SocketCanBus sending `frames` as fast as it can; if any are lost,
/// again paced below the rate reached, until none are (the highest lossless rate).
RateFigures canhil_rate(const std::string& iface, std::uint64_t frames);
/// `cangen IFACE -g 0 -p 10 -n FRAMES` (polling on a full queue: no sender drops).
RateFigures cangen_rate(const std::string& iface, std::uint64_t frames);

}  // namespace canhil::app
