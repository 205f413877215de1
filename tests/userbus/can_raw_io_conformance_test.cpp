// CAN_RAW conformance, continued (can_raw_conformance_test.cpp says how the
// program runs): FD frames and the MTU, timestamps, the receive queue's
// overflow, many frames a call, poll/select/epoll, a socket shared by dup,
// fork and exec, a downed interface, and calls a CAN socket does not take.
//
// Started with CANHIL_CONFORMANCE_EXEC_FD=N, the program is the far side of
// the exec test instead: it reads one frame from descriptor N (inherited
// across exec) and writes it back with its id plus one.
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/sock_diag.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/ioctl.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>

#include "can_raw_support.hpp"

namespace canhil::test::can_raw {
namespace {

/// Sets interface `name`'s MTU (down, SIOCSIFMTU, up again).
void set_mtu(int fd, const char* name, int mtu) {
  ifreq r{};
  name_into(r, name);
  ASSERT_EQ(ioctl(fd, SIOCGIFFLAGS, &r), 0);
  const short up = r.ifr_flags;
  r.ifr_flags = static_cast<short>(up & ~IFF_UP);
  ASSERT_EQ(ioctl(fd, SIOCSIFFLAGS, &r), 0);
  r.ifr_mtu = mtu;
  ASSERT_EQ(ioctl(fd, SIOCSIFMTU, &r), 0) << std::strerror(errno);
  r.ifr_flags = static_cast<short>(up | IFF_UP);
  ASSERT_EQ(ioctl(fd, SIOCSIFFLAGS, &r), 0);
}

TEST_F(CanRaw, FdFramesAndTheInterfacesMtu) {
  Sock tx, fd_rx, classic_rx, classic_tx;
  ASSERT_EQ(tx.set(SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1), 0);
  ASSERT_EQ(fd_rx.set(SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1), 0);
  for (const Sock* s : {&tx, &fd_rx, &classic_rx, &classic_tx}) ASSERT_EQ(s->bind_to(vcan0), 0);
  canfd_frame fd{};
  fd.can_id = 0x5;
  fd.len = 12;
  fd.flags = CANFD_BRS;
  ASSERT_EQ(write(tx.fd(), &fd, sizeof fd), static_cast<ssize_t>(CANFD_MTU));
  const auto r = receive(fd_rx.fd());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->size, static_cast<ssize_t>(CANFD_MTU));
  EXPECT_EQ(count_frames(classic_rx.fd()), 0);            // an FD frame reaches FD sockets only
  EXPECT_EQ(write(classic_tx.fd(), &fd, sizeof fd), -1);  // not without CAN_RAW_FD_FRAMES
  EXPECT_EQ(errno, EINVAL);
  fd.len = 65;
  EXPECT_EQ(write(tx.fd(), &fd, sizeof fd), -1);
  EXPECT_EQ(errno, EINVAL);
  ASSERT_GT(send_frame(tx.fd(), frame(0x6, {1})), 0);  // a classic frame is 16 bytes, also to an FD socket
  const auto c = receive(fd_rx.fd());
  ASSERT_TRUE(c);
  EXPECT_EQ(c->size, static_cast<ssize_t>(CAN_MTU));
  // an interface of MTU 16 takes classic frames only
  Sock ctl, on1;
  ifreq busy{};
  name_into(busy, "vcan1");
  busy.ifr_mtu = CAN_MTU;
  EXPECT_EQ(ioctl(ctl.fd(), SIOCSIFMTU, &busy), -1);  // not while it is up
  EXPECT_EQ(errno, EBUSY);
  set_mtu(ctl.fd(), "vcan1", CAN_MTU);
  ASSERT_EQ(on1.set(SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1), 0);
  ASSERT_EQ(on1.bind_to(vcan1), 0);
  fd.len = 12;
  EXPECT_EQ(write(on1.fd(), &fd, sizeof fd), -1);
  EXPECT_EQ(errno, EINVAL);
  EXPECT_GT(send_frame(on1.fd(), frame(0x7)), 0);
  set_mtu(ctl.fd(), "vcan1", CANFD_MTU);
}

TEST_F(CanRaw, TimestampsInControlMessagesAndSiocgstamp) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  timeval tv{};
  EXPECT_EQ(ioctl(rx.fd(), SIOCGSTAMP, &tv), -1);  // no frame read yet
  EXPECT_EQ(errno, ENOENT);
  // asked once, SIOCGSTAMP gives the time of the last frame read
  std::int64_t before = now_ns();
  ASSERT_GT(send_frame(tx.fd(), frame(0x1F)), 0);
  ASSERT_TRUE(receive(rx.fd()));
  std::int64_t after = now_ns();
  ASSERT_EQ(ioctl(rx.fd(), SIOCGSTAMP, &tv), 0);
  const std::int64_t kept = static_cast<std::int64_t>(tv.tv_sec) * 1000000000 + tv.tv_usec * 1000;
  // between the send and the read, give or take the VM's clock skew between
  // the kernel's stamp and the vDSO's clock (2 ms)
  EXPECT_GE(kept, before - kSkew);
  EXPECT_LE(kept, after + kSkew);
  // SO_TIMESTAMP: the time in a control message of each frame
  ASSERT_EQ(rx.set(SOL_SOCKET, SO_TIMESTAMP, 1), 0);
  before = now_ns();
  ASSERT_GT(send_frame(tx.fd(), frame(0x20)), 0);
  const auto r = receive(rx.fd(), 200, 256);
  after = now_ns();
  ASSERT_TRUE(r);
  ASSERT_GE(r->control.size(), CMSG_LEN(sizeof(timeval)));
  const auto* c = reinterpret_cast<const cmsghdr*>(r->control.data());
  EXPECT_EQ(c->cmsg_level, SOL_SOCKET);
  EXPECT_EQ(c->cmsg_type, SCM_TIMESTAMP);
  timeval got{};
  std::memcpy(&got, CMSG_DATA(c), sizeof got);
  const std::int64_t at = static_cast<std::int64_t>(got.tv_sec) * 1000000000 + got.tv_usec * 1000;
  EXPECT_GE(at, before - kSkew);
  EXPECT_LE(at, after + kSkew);
  // nanoseconds
  ASSERT_EQ(rx.set(SOL_SOCKET, SO_TIMESTAMPNS, 1), 0);
  int v = -1;
  socklen_t len = sizeof v;
  ASSERT_EQ(getsockopt(rx.fd(), SOL_SOCKET, SO_TIMESTAMP, &v, &len), 0);
  EXPECT_EQ(v, 0);  // the nanosecond stamp replaces the microsecond one
  ASSERT_GT(send_frame(tx.fd(), frame(0x21)), 0);
  const auto n = receive(rx.fd(), 200, 256);
  ASSERT_TRUE(n);
  ASSERT_GE(n->control.size(), CMSG_LEN(sizeof(timespec)));
  const auto* cn = reinterpret_cast<const cmsghdr*>(n->control.data());
  EXPECT_EQ(cn->cmsg_type, SCM_TIMESTAMPNS);
  // no room for the control message: MSG_CTRUNC
  ASSERT_GT(send_frame(tx.fd(), frame(0x22)), 0);
  const auto t = receive(rx.fd(), 200, 4);
  ASSERT_TRUE(t);
  EXPECT_NE(t->flags & MSG_CTRUNC, 0);
}

/// The SO_RXQ_OVFL count a frame carries, or nothing.
std::optional<std::uint32_t> drops_of(const Received& r) {
  msghdr m{};
  m.msg_control = const_cast<std::uint8_t*>(r.control.data());
  m.msg_controllen = r.control.size();
  for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      std::uint32_t n = 0;
      std::memcpy(&n, CMSG_DATA(c), sizeof n);
      return n;
    }
  }
  return std::nullopt;
}

TEST_F(CanRaw, ReceiveBufferOverflowIsCountedAndReported) {
  Sock tx(SOCK_NONBLOCK), rx;
  ASSERT_EQ(rx.set(SOL_SOCKET, SO_RCVBUF, 4096), 0);
  int v = 0;
  socklen_t len = sizeof v;
  ASSERT_EQ(getsockopt(rx.fd(), SOL_SOCKET, SO_RCVBUF, &v, &len), 0);
  EXPECT_EQ(v, 8192);  // the kernel doubles what is asked
  ASSERT_EQ(rx.set(SOL_SOCKET, SO_RXQ_OVFL, 1), 0);
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  constexpr int kSent = 3000;
  for (int k = 0; k < kSent; ++k) {
    ASSERT_EQ(send_frame(tx.fd(), frame(static_cast<canid_t>(k & 0x7FF))), static_cast<ssize_t>(sizeof(can_frame)))
        << "write " << k << " of a non-blocking socket: " << std::strerror(errno);
  }
  // A vcan delivers inside write(); a real controller and the user-space bus
  // deliver after it returns. Reading only once the bus is quiet makes the
  // count the same on both.
  usleep(200000);
  int received = 0;
  while (auto r = receive(rx.fd(), 200, 256)) {
    ++received;
    EXPECT_FALSE(drops_of(*r)) << "frame " << received << " was queued before any drop";
  }
  EXPECT_GT(received, 0);  // the buffer held some
  EXPECT_LT(received, kSent);
  // The next frame queued carries the count of those dropped before it: every frame sent is one or the other.
  ASSERT_GT(send_frame(tx.fd(), frame(0x7FF)), 0);
  const auto last = receive(rx.fd(), 200, 256);
  ASSERT_TRUE(last);
  const auto drops = drops_of(*last);
  ASSERT_TRUE(drops);
  EXPECT_EQ(static_cast<int>(*drops) + received, kSent);
  // SO_MEMINFO counts the same drops
  std::uint32_t info[SK_MEMINFO_VARS] = {};
  socklen_t info_size = sizeof info;
  ASSERT_EQ(getsockopt(rx.fd(), SOL_SOCKET, SO_MEMINFO, info, &info_size), 0);
  EXPECT_EQ(info[SK_MEMINFO_DROPS], *drops);
  EXPECT_EQ(info[SK_MEMINFO_RCVBUF], 8192U);
}

TEST_F(CanRaw, ManyFramesAtOnceWithSendmmsgAndRecvmmsg) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  can_frame out[5];
  iovec out_v[5];
  mmsghdr out_m[5] = {};
  for (int k = 0; k < 5; ++k) {
    out[k] = frame(static_cast<canid_t>(0x300 + k), {k});
    out_v[k] = {&out[k], sizeof out[k]};
    out_m[k].msg_hdr.msg_iov = &out_v[k];
    out_m[k].msg_hdr.msg_iovlen = 1;
  }
  ASSERT_EQ(sendmmsg(tx.fd(), out_m, 5, 0), 5);
  ASSERT_TRUE(readable(rx.fd(), 200));
  usleep(20000);
  can_frame in[5] = {};
  iovec in_v[5];
  mmsghdr in_m[5] = {};
  for (int k = 0; k < 5; ++k) {
    in_v[k] = {&in[k], sizeof in[k]};
    in_m[k].msg_hdr.msg_iov = &in_v[k];
    in_m[k].msg_hdr.msg_iovlen = 1;
  }
  ASSERT_EQ(recvmmsg(rx.fd(), in_m, 5, MSG_DONTWAIT, nullptr), 5);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(in[k].can_id, static_cast<canid_t>(0x300 + k));
    EXPECT_EQ(in_m[k].msg_len, sizeof(can_frame));
  }
}

TEST_F(CanRaw, PollSelectEpollAndNonBlocking) {
  Sock tx, rx(SOCK_NONBLOCK);
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  can_frame f{};
  EXPECT_EQ(read(rx.fd(), &f, sizeof f), -1);
  EXPECT_EQ(errno, EAGAIN);
  pollfd p{rx.fd(), POLLIN, 0};
  EXPECT_EQ(poll(&p, 1, 0), 0);
  const int ep = epoll_create1(0);
  epoll_event e{};
  e.events = EPOLLIN;
  e.data.fd = rx.fd();
  ASSERT_EQ(epoll_ctl(ep, EPOLL_CTL_ADD, rx.fd(), &e), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x33)), 0);
  epoll_event got{};
  EXPECT_EQ(epoll_wait(ep, &got, 1, 500), 1);
  close(ep);
  fd_set set;
  FD_ZERO(&set);
  FD_SET(rx.fd(), &set);
  timeval limit{0, 500000};
  EXPECT_EQ(select(rx.fd() + 1, &set, nullptr, nullptr, &limit), 1);
  EXPECT_EQ(read(rx.fd(), &f, sizeof f), static_cast<ssize_t>(sizeof f));
  EXPECT_EQ(f.can_id, 0x33U);
  // a socket is writable when idle
  pollfd w{tx.fd(), POLLOUT, 0};
  EXPECT_EQ(poll(&w, 1, 0), 1);
}

TEST_F(CanRaw, DupForkAndExecShareTheSocket) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  const int copy = dup(rx.fd());
  ASSERT_GE(copy, 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x44)), 0);
  ASSERT_TRUE(readable(copy, 200));
  can_frame f{};
  EXPECT_EQ(read(copy, &f, sizeof f), static_cast<ssize_t>(sizeof f));
  EXPECT_EQ(f.can_id, 0x44U);
  close(copy);
  // a forked child sends on the inherited socket
  const pid_t child = fork();
  if (child == 0) _exit(send_frame(tx.fd(), frame(0x45)) == static_cast<ssize_t>(sizeof(can_frame)) ? 0 : 1);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const auto r = receive(rx.fd());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame.can_id, 0x45U);
  // a program exec'd with the socket reads from it and answers on it
  Sock far;
  ASSERT_EQ(far.bind_to(vcan0), 0);
  ASSERT_EQ(far.set_filters({{0x60, 0x7FF}}), 0);
  const pid_t runner = fork();
  if (runner == 0) {
    const std::string fd = std::to_string(far.fd());
    setenv("CANHIL_CONFORMANCE_EXEC_FD", fd.c_str(), 1);
    execl("/proc/self/exe", "can_raw_conformance", static_cast<char*>(nullptr));
    _exit(127);
  }
  usleep(200000);
  ASSERT_GT(send_frame(tx.fd(), frame(0x60, {7})), 0);
  ASSERT_EQ(waitpid(runner, &status, 0), runner);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the exec'd program: status " << status;
  bool answered = false;
  while (auto a = receive(rx.fd(), 200)) answered = answered || a->frame.can_id == 0x61U;
  EXPECT_TRUE(answered);
}

TEST_F(CanRaw, DownedInterfaceAnswersEnetdown) {
  Sock ctl, tx, rx;
  ASSERT_EQ(tx.bind_to(vcan1), 0);
  ASSERT_EQ(rx.bind_to(vcan1), 0);
  ifreq r{};
  name_into(r, "vcan1");
  ASSERT_EQ(ioctl(ctl.fd(), SIOCGIFFLAGS, &r), 0);
  r.ifr_flags = static_cast<short>(r.ifr_flags & ~IFF_UP);
  ASSERT_EQ(ioctl(ctl.fd(), SIOCSIFFLAGS, &r), 0) << std::strerror(errno);
  can_frame f{};
  EXPECT_EQ(read(rx.fd(), &f, sizeof f), -1);  // told once
  EXPECT_EQ(errno, ENETDOWN);
  EXPECT_EQ(send_frame(tx.fd(), frame(0x50)), -1);
  EXPECT_EQ(errno, ENETDOWN);
  Sock late;
  EXPECT_EQ(late.bind_to(vcan1), 0);  // binding a downed interface works, and reports it
  int e = 0;
  socklen_t len = sizeof e;
  ASSERT_EQ(getsockopt(late.fd(), SOL_SOCKET, SO_ERROR, &e, &len), 0);
  EXPECT_EQ(e, ENETDOWN);
  r.ifr_flags = static_cast<short>(r.ifr_flags | IFF_UP);
  ASSERT_EQ(ioctl(ctl.fd(), SIOCSIFFLAGS, &r), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x51)), 0);
  const auto back = receive(rx.fd());
  ASSERT_TRUE(back);
  EXPECT_EQ(back->frame.can_id, 0x51U);
}

TEST_F(CanRaw, CallsACanSocketDoesNotTake) {
  Sock s;
  sockaddr_can a{};
  a.can_family = AF_CAN;
  a.can_ifindex = vcan0;
  EXPECT_EQ(connect(s.fd(), reinterpret_cast<sockaddr*>(&a), sizeof a), -1);
  EXPECT_EQ(errno, EOPNOTSUPP);
  EXPECT_EQ(listen(s.fd(), 1), -1);
  EXPECT_EQ(errno, EOPNOTSUPP);
  socklen_t len = sizeof a;
  EXPECT_EQ(getpeername(s.fd(), reinterpret_cast<sockaddr*>(&a), &len), -1);
  EXPECT_EQ(errno, EOPNOTSUPP);
  int n = 0;
  EXPECT_EQ(ioctl(s.fd(), FIONREAD, &n), -1);
  EXPECT_EQ(errno, ENOTTY);
}

/// The exec test's far side: one frame in, its id plus one back.
int exec_child(int fd) {
  if (!readable(fd, 2000)) return 2;
  can_frame f{};
  if (read(fd, &f, sizeof f) != static_cast<ssize_t>(sizeof f) || f.can_id != 0x60) return 3;
  f.can_id += 1;
  return write(fd, &f, sizeof f) == static_cast<ssize_t>(sizeof f) ? 0 : 4;
}

}  // namespace
}  // namespace canhil::test::can_raw

int main(int argc, char** argv) {
  if (const char* fd = std::getenv("CANHIL_CONFORMANCE_EXEC_FD"))
    return canhil::test::can_raw::exec_child(static_cast<int>(std::strtol(fd, nullptr, 10)));
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
