// canhil/laptop/raw_can.hpp — the laptop side's own minimal SocketCAN socket.
// The reference laptop stack uses no emulator code, as a team's own would not.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include "canhil/frames/frame.hpp"

namespace canhil::laptop {

class RawCan {
 public:
  /// Opens a non-blocking CAN_RAW socket on `iface` with kernel receive
  /// timestamps. Throws std::runtime_error saying what to do.
  explicit RawCan(const std::string& iface);
  ~RawCan();
  RawCan(const RawCan&) = delete;
  RawCan& operator=(const RawCan&) = delete;

  bool send(const frames::CanFrame& frame);
  /// The next frame and its kernel receive time (CLOCK_REALTIME), if any.
  std::optional<frames::TimedFrame> receive();
  int fd() const noexcept { return fd_; }

 private:
  int fd_ = -1;
};

}  // namespace canhil::laptop
