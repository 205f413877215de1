// The kernel's CAN_RAW receive rules as the broker applies them: a socket's
// filters registered as af_can.c registers them, and whether a socket's
// options take a frame (raw.c's raw_rcv, joined filters included).
#pragma once

#include <linux/can.h>

#include <cstdint>
#include <vector>

namespace canhil::userbus {

struct Socket;
struct State;

/// A filter as the kernel registers it (af_can.c, can_rcv_list_find): the
/// mask reduced, the id masked, and its list (error, inverted or plain).
struct Registered {
  canid_t id;
  canid_t mask;
  bool error;
  bool inverted;
};

/// What the broker keeps of a socket's options, refreshed when its seq moves.
struct Options {
  std::uint32_t seq = ~0U;
  std::int32_t ifindex = 0;
  bool bound = false;
  std::uint32_t flags = 0;
  std::int32_t rcvbuf = 0;
  std::uint32_t count = 0;          // the user's filters (joined filters must all match)
  bool single_ids = false;          // every filter takes one standard or extended id (the kernel serves those last)
  std::vector<Registered> filters;  // the user's, then the error filter if any
  // single_ids: the filters' ids, sorted, standard and extended apart (a
  // delivery fence's 512 filters a socket are a search, not 512 tests a frame).
  std::vector<canid_t> standard_ids;
  std::vector<canid_t> extended_ids;
};

/// The options of socket `s` as they stand (read under its seqlock by the
/// caller: `seq` is the even value it saw before).
Options options_of(const Socket& s, std::uint32_t seq);

/// The options of socket `s` as the processes last wrote them: a seqlock read.
Options read_options(const Socket& s);

/// Whether socket options `o` take a frame of `can_id` (raw_rcv's rules:
/// any filter, or every filter when they are joined).
bool wants(const Options& o, canid_t can_id);

/// A new socket of process `pid`, whose connection's broker end is `fd`: a
/// free slot of `state` with raw_init's options (loopback on, one filter
/// that takes every frame, no error mask). The slot, or -ENOBUFS when none is free.
int claim_socket(State& state, std::int32_t pid, int fd);

}  // namespace canhil::userbus
