// The kernel's CAN_RAW receive rules as the broker applies them (broker_filters.hpp).
#include "broker_filters.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <sys/socket.h>
#include <sys/un.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "canhil/userbus/state.hpp"

namespace canhil::userbus {
namespace {

Registered register_filter(canid_t id, canid_t mask) {
  const bool inverted = (id & CAN_INV_FILTER) != 0;
  if ((mask & CAN_ERR_FLAG) != 0) return {id, mask & CAN_ERR_MASK, true, false};
  if ((mask & CAN_EFF_FLAG) != 0 && (id & CAN_EFF_FLAG) == 0) mask &= (CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG);
  return {id & mask, mask, false, inverted};
}

bool matches(const Registered& r, canid_t can_id) {
  if ((can_id & CAN_ERR_FLAG) != 0) return r.error && (can_id & r.mask) != 0;
  if (r.error) return false;
  const bool equal = (can_id & r.mask) == r.id;
  return r.inverted ? !equal : equal;
}

}  // namespace

Options options_of(const Socket& s, std::uint32_t seq) {
  Options o;
  o.seq = seq;
  o.ifindex = s.ifindex;
  o.bound = s.bound != 0;
  o.flags = s.flags;
  o.rcvbuf = s.rcvbuf;
  o.count = std::min<std::uint32_t>(s.filter_count, kMaxFilters);
  o.filters.reserve(o.count + 1);
  for (std::uint32_t f = 0; f < o.count; ++f)
    o.filters.push_back(register_filter(s.filters[f].can_id, s.filters[f].can_mask));
  o.single_ids = o.count > 0;
  for (std::uint32_t f = 0; f < o.count; ++f) {
    const canid_t id = s.filters[f].can_id;
    const canid_t mask = s.filters[f].can_mask;
    const canid_t flags = CAN_EFF_FLAG | CAN_RTR_FLAG;
    const bool one = (id & (CAN_INV_FILTER | CAN_RTR_FLAG)) == 0 &&
                     (mask == (CAN_SFF_MASK | flags) || ((id & CAN_EFF_FLAG) != 0 && mask == (CAN_EFF_MASK | flags)));
    o.single_ids = o.single_ids && one;
  }
  if (o.single_ids) {
    for (const Registered& r : o.filters)
      ((r.id & CAN_EFF_FLAG) != 0 ? o.extended_ids : o.standard_ids).push_back(r.id);
    std::sort(o.standard_ids.begin(), o.standard_ids.end());
    std::sort(o.extended_ids.begin(), o.extended_ids.end());
  }
  if ((s.err_mask & CAN_ERR_MASK) != 0)
    o.filters.push_back(register_filter(0, (s.err_mask & CAN_ERR_MASK) | CAN_ERR_FLAG));
  return o;
}

bool wants(const Options& o, canid_t can_id) {
  const bool joined = (o.flags & kJoinFilters) != 0 && o.count > 1;
  if (!joined && o.single_ids && (can_id & CAN_ERR_FLAG) == 0) {
    // A single-id filter's mask keeps the id, the EFF and the RTR flags (11
    // bits of the id for a standard one, 29 for an extended one).
    constexpr canid_t kFlags = CAN_EFF_FLAG | CAN_RTR_FLAG;
    return std::binary_search(o.standard_ids.begin(), o.standard_ids.end(), can_id & (CAN_SFF_MASK | kFlags)) ||
           std::binary_search(o.extended_ids.begin(), o.extended_ids.end(), can_id & (CAN_EFF_MASK | kFlags));
  }
  std::uint32_t hits = 0;
  for (const Registered& r : o.filters) {
    if (!matches(r, can_id)) continue;
    if (!joined) return true;
    ++hits;
  }
  return hits > 0 && hits >= o.count;
}

Options read_options(const Socket& s) {
  for (;;) {
    const std::uint32_t before = s.seq.load(std::memory_order_acquire);
    if ((before & 1U) != 0) continue;
    Options o = options_of(s, before);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (s.seq.load(std::memory_order_relaxed) == before) return o;
  }
}

int claim_socket(State& state, std::int32_t pid, int fd) {
  for (int k = 0; k < kMaxSockets; ++k) {
    Socket& s = state.sockets[k];
    if (s.in_use.load(std::memory_order_acquire) != 0) continue;
    s.lock.lock();
    s.pid = pid;
    s.ifindex = 0;
    s.bound = 0;
    s.flags = kLoopback;
    s.err_mask = 0;
    s.rcvbuf = 0;
    s.sndbuf = 0;
    s.filter_count = 1;  // raw_init: one filter that takes every frame
    s.filters[0] = can_filter{0, 0};
    sockaddr_un peer{};
    socklen_t len = sizeof peer;
    std::memset(s.peer, 0, sizeof s.peer);
    if (getpeername(fd, reinterpret_cast<sockaddr*>(&peer), &len) == 0 && len > sizeof(sa_family_t)) {
      std::memcpy(s.peer, peer.sun_path, std::min<std::size_t>(len - sizeof(sa_family_t), sizeof s.peer));
    }
    s.pending_error.store(0);
    s.last_stamp_ns.store(-1);
    s.drops.store(0);
    s.received.store(0);
    s.sent.store(0);
    s.taken.store(0);
    s.seq.fetch_add(2, std::memory_order_release);
    s.lock.unlock();
    s.in_use.store(1, std::memory_order_release);
    return k;
  }
  return -ENOBUFS;
}

}  // namespace canhil::userbus
