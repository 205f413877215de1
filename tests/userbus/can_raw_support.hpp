// tests/userbus/can_raw_support.hpp — what the CAN_RAW conformance program's
// tests share: a socket, frames, receiving with the message's address, flags
// and control data, and the fixture that finds vcan0 and vcan1.
#pragma once

#include <linux/can.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <optional>
#include <vector>

namespace canhil::test::can_raw {

inline int index_of(const char* name) { return static_cast<int>(if_nametoindex(name)); }

/// `name` into an interface request.
inline void name_into(ifreq& r, const char* name) { std::snprintf(r.ifr_name, IFNAMSIZ, "%s", name); }

class Sock {
 public:
  explicit Sock(int flags = 0) : fd_(socket(PF_CAN, SOCK_RAW | flags, CAN_RAW)) {}
  ~Sock() {
    if (fd_ >= 0) close(fd_);
  }
  Sock(const Sock&) = delete;
  Sock& operator=(const Sock&) = delete;
  int fd() const { return fd_; }
  int bind_to(int ifindex) const {
    sockaddr_can a{};
    a.can_family = AF_CAN;
    a.can_ifindex = ifindex;
    return bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
  }
  template <class T>
  int set(int level, int name, const T& value) const {
    return setsockopt(fd_, level, name, &value, sizeof value);
  }
  int set_filters(const std::vector<can_filter>& f) const {
    return setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, f.empty() ? nullptr : f.data(),
                      static_cast<socklen_t>(f.size() * sizeof(can_filter)));
  }

 private:
  int fd_;
};

inline can_frame frame(canid_t id, std::initializer_list<int> data = {}) {
  can_frame f{};
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(data.size());
  int k = 0;
  for (int d : data) f.data[k++] = static_cast<std::uint8_t>(d);
  return f;
}

inline bool readable(int fd, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, timeout_ms) > 0 && (p.revents & POLLIN) != 0;
}

struct Received {
  canfd_frame frame{};  // room for an FD frame; a classic one fills its first 16 bytes
  sockaddr_can from{};
  socklen_t from_size = 0;
  int flags = 0;
  std::vector<std::uint8_t> control;
  ssize_t size = 0;
};

/// One frame within `timeout_ms`, or nothing.
inline std::optional<Received> receive(int fd, int timeout_ms = 200, std::size_t control_room = 0) {
  if (!readable(fd, timeout_ms)) return std::nullopt;
  Received r;
  iovec v{&r.frame, sizeof r.frame};
  r.control.resize(control_room);
  msghdr m{};
  m.msg_name = &r.from;
  m.msg_namelen = sizeof r.from;
  m.msg_iov = &v;
  m.msg_iovlen = 1;
  m.msg_control = control_room > 0 ? r.control.data() : nullptr;
  m.msg_controllen = control_room;
  r.size = recvmsg(fd, &m, 0);
  if (r.size < 0) return std::nullopt;
  r.from_size = m.msg_namelen;
  r.flags = m.msg_flags;
  r.control.resize(m.msg_controllen);
  return r;
}

/// How many frames arrive at `fd` until it stays quiet for `quiet_ms`.
inline int count_frames(int fd, int quiet_ms = 100) {
  int n = 0;
  while (receive(fd, quiet_ms)) ++n;
  return n;
}

inline ssize_t send_frame(int fd, const can_frame& f) { return write(fd, &f, sizeof f); }

/// An address no program may read or write (the first page), as the compiler cannot see it.
inline void* bad_address() {
  static volatile std::uintptr_t at = 8;
  return reinterpret_cast<void*>(at);  // NOLINT(performance-no-int-to-ptr): an address that is no object's, on purpose
}

inline constexpr std::int64_t kSkew = 2'000'000;  // ns

inline std::int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_REALTIME, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1000000000 + t.tv_nsec;
}

class CanRaw : public ::testing::Test {
 protected:
  void SetUp() override {
    vcan0 = index_of("vcan0");
    vcan1 = index_of("vcan1");
    ASSERT_GT(vcan0, 0) << "this suite needs interfaces vcan0 and vcan1";
    ASSERT_GT(vcan1, 0);
  }
  int vcan0 = 0;
  int vcan1 = 0;
};

}  // namespace canhil::test::can_raw
