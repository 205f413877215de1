// One connection to the broker as the broker keeps it: a program's CAN_RAW
// socket (its slot in the state file, its options as last read, what was
// routed to it and waits) or a control connection. Private to broker.cpp.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include "broker_filters.hpp"
#include "canhil/userbus/state.hpp"

namespace canhil::userbus {

struct Connection {
  int fd = -1;
  int slot = -1;  // -1 until its hello, and for a control connection
  bool control = false;
  bool hello = false;
  bool overrun = false;  // stuck with a full backlog past the grace: drop at once until it reads
  std::int32_t applied_rcvbuf = 0;
  Options options;
  std::vector<RxRecord> queued;  // routed in this round, sent together at its end
  std::deque<RxRecord> backlog;  // routed, but its buffer was full: sent, in order, as it reads
  bool backlogged = false;       // backlog not empty (EPOLLOUT watched)
  std::uint64_t opened = 0;      // the order connections were opened in
};

}  // namespace canhil::userbus
