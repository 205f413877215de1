// CAN_RAW as the kernel documents it (Documentation/networking/can.rst), one
// test per point, for two backends with the same expectations: this program,
// built once, runs against the kernel's vcan in the VM runner
// (vcan.can_raw_conformance) and against the user-space bus natively, under
// `canhil bus exec` (userbus.can_raw_conformance). Interfaces vcan0 and vcan1,
// both up. A difference between the backends fails here.
//
// Here: the socket, its interfaces and binding, filters, error frames,
// loopback, options and what is refused. The frames' sizes and times, the
// ways of waiting and sharing, and the program's main are in
// can_raw_io_conformance_test.cpp.
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <linux/sockios.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "can_raw_support.hpp"

namespace canhil::test::can_raw {
namespace {

TEST_F(CanRaw, SocketIsARealDescriptorOfTheCanFamily) {
  Sock s;
  ASSERT_GE(s.fd(), 0) << std::strerror(errno);
  int v = 0;
  socklen_t len = sizeof v;
  ASSERT_EQ(getsockopt(s.fd(), SOL_SOCKET, SO_DOMAIN, &v, &len), 0);
  EXPECT_EQ(v, AF_CAN);
  ASSERT_EQ(getsockopt(s.fd(), SOL_SOCKET, SO_TYPE, &v, &len), 0);
  EXPECT_EQ(v, SOCK_RAW);
  ASSERT_EQ(getsockopt(s.fd(), SOL_SOCKET, SO_PROTOCOL, &v, &len), 0);
  EXPECT_EQ(v, 0);  // can_create leaves the protocol unset
  EXPECT_EQ(socket(PF_CAN, SOCK_DGRAM, CAN_RAW), -1);
  EXPECT_EQ(errno, EPROTOTYPE);
}

TEST_F(CanRaw, InterfaceNamesAndIndices) {
  char name[IF_NAMESIZE] = {};
  ASSERT_NE(if_indextoname(static_cast<unsigned>(vcan0), name), nullptr);
  EXPECT_STREQ(name, "vcan0");
  Sock s;
  ifreq r{};
  name_into(r, "vcan1");
  ASSERT_EQ(ioctl(s.fd(), SIOCGIFINDEX, &r), 0);
  EXPECT_EQ(r.ifr_ifindex, vcan1);
  ifreq back{};
  back.ifr_ifindex = vcan1;
  ASSERT_EQ(ioctl(s.fd(), SIOCGIFNAME, &back), 0);
  EXPECT_STREQ(back.ifr_name, "vcan1");
  ASSERT_EQ(ioctl(s.fd(), SIOCGIFMTU, &r), 0);
  EXPECT_EQ(r.ifr_mtu, static_cast<int>(CANFD_MTU));  // a vcan's default
  ASSERT_EQ(ioctl(s.fd(), SIOCGIFFLAGS, &r), 0);
  EXPECT_NE(r.ifr_flags & IFF_UP, 0);
  EXPECT_EQ(if_nametoindex("nosuchcan7"), 0U);
  ifreq none{};
  name_into(none, "nosuchcan7");
  EXPECT_EQ(ioctl(s.fd(), SIOCGIFINDEX, &none), -1);
  EXPECT_EQ(errno, ENODEV);
  EXPECT_EQ(ioctl(s.fd(), SIOCGIFINDEX, bad_address()), -1);
  EXPECT_EQ(errno, EFAULT);
}

TEST_F(CanRaw, BindToOneInterfaceOrToAll) {
  Sock tx, on0, on1, all;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(on0.bind_to(vcan0), 0);
  ASSERT_EQ(on1.bind_to(vcan1), 0);
  ASSERT_EQ(all.bind_to(0), 0);
  ASSERT_EQ(send_frame(tx.fd(), frame(0x123, {1, 2})), static_cast<ssize_t>(sizeof(can_frame)));
  const auto a = receive(on0.fd());
  ASSERT_TRUE(a);
  EXPECT_EQ(a->frame.can_id, 0x123U);
  EXPECT_EQ(a->frame.len, 2);
  EXPECT_EQ(a->from.can_family, AF_CAN);
  EXPECT_EQ(a->from.can_ifindex, vcan0);
  const auto b = receive(all.fd());
  ASSERT_TRUE(b);
  EXPECT_EQ(b->from.can_ifindex, vcan0);
  EXPECT_FALSE(receive(on1.fd(), 50));
  // recvfrom names the interface a frame came on
  Sock tx1;
  ASSERT_EQ(tx1.bind_to(vcan1), 0);
  ASSERT_EQ(send_frame(tx1.fd(), frame(0x7FF)), static_cast<ssize_t>(sizeof(can_frame)));
  ASSERT_TRUE(readable(all.fd(), 200));
  can_frame f{};
  sockaddr_can from{};
  socklen_t size = sizeof from;
  ASSERT_EQ(recvfrom(all.fd(), &f, sizeof f, 0, reinterpret_cast<sockaddr*>(&from), &size),
            static_cast<ssize_t>(sizeof f));
  EXPECT_EQ(from.can_ifindex, vcan1);
  EXPECT_EQ(size, 8U);  // RAW_MIN_NAMELEN: the family and the index
  // getsockname says where a socket is bound
  sockaddr_can self{};
  socklen_t self_size = sizeof self;
  ASSERT_EQ(getsockname(on1.fd(), reinterpret_cast<sockaddr*>(&self), &self_size), 0);
  EXPECT_EQ(self.can_family, AF_CAN);
  EXPECT_EQ(self.can_ifindex, vcan1);
}

TEST_F(CanRaw, SendtoNamesTheInterface) {
  Sock tx, on1;
  ASSERT_EQ(tx.bind_to(0), 0);
  ASSERT_EQ(on1.bind_to(vcan1), 0);
  sockaddr_can to{};
  to.can_family = AF_CAN;
  to.can_ifindex = vcan1;
  const can_frame f = frame(0x42, {9});
  ASSERT_EQ(sendto(tx.fd(), &f, sizeof f, 0, reinterpret_cast<sockaddr*>(&to), sizeof to),
            static_cast<ssize_t>(sizeof f));
  const auto r = receive(on1.fd());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame.can_id, 0x42U);
  // bound to all, no address: no interface to send on
  EXPECT_EQ(send_frame(tx.fd(), f), -1);
  EXPECT_EQ(errno, ENXIO);
}

TEST_F(CanRaw, FiltersOfIdAndMask) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.set_filters({{0x120, 0x7F0}}), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  for (canid_t id : {0x120U, 0x12FU, 0x130U, 0x220U}) ASSERT_GT(send_frame(tx.fd(), frame(id)), 0);
  std::vector<canid_t> got;
  while (auto r = receive(rx.fd(), 100)) got.push_back(r->frame.can_id);
  EXPECT_EQ(got, (std::vector<canid_t>{0x120, 0x12F}));
}

TEST_F(CanRaw, InvertedFilter) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.set_filters({{0x123 | CAN_INV_FILTER, CAN_SFF_MASK}}), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  for (canid_t id : {0x123U, 0x124U}) ASSERT_GT(send_frame(tx.fd(), frame(id)), 0);
  std::vector<canid_t> got;
  while (auto r = receive(rx.fd(), 100)) got.push_back(r->frame.can_id);
  EXPECT_EQ(got, (std::vector<canid_t>{0x124}));
}

TEST_F(CanRaw, ExtendedAndRemoteFlagsInIdAndMask) {
  Sock tx, sff_only, eff_only, rtr_only;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  // id 0x123 with the EFF flag in the mask: standard frames of 0x123 only
  ASSERT_EQ(sff_only.set_filters({{0x123, CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_SFF_MASK}}), 0);
  ASSERT_EQ(eff_only.set_filters({{0x123 | CAN_EFF_FLAG, CAN_EFF_FLAG | CAN_EFF_MASK}}), 0);
  ASSERT_EQ(rtr_only.set_filters({{CAN_RTR_FLAG, CAN_RTR_FLAG}}), 0);
  for (const Sock* s : {&sff_only, &eff_only, &rtr_only}) ASSERT_EQ(s->bind_to(vcan0), 0);
  for (canid_t id : {0x123U, 0x123U | CAN_EFF_FLAG, 0x123U | CAN_RTR_FLAG, 0x555U | CAN_RTR_FLAG}) {
    ASSERT_GT(send_frame(tx.fd(), frame(id)), 0);
  }
  auto ids = [](int fd) {
    std::vector<canid_t> got;
    while (auto r = receive(fd, 100)) got.push_back(r->frame.can_id);
    return got;
  };
  EXPECT_EQ(ids(sff_only.fd()), (std::vector<canid_t>{0x123}));
  EXPECT_EQ(ids(eff_only.fd()), (std::vector<canid_t>{0x123 | CAN_EFF_FLAG}));
  EXPECT_EQ(ids(rtr_only.fd()), (std::vector<canid_t>{0x123 | CAN_RTR_FLAG, 0x555 | CAN_RTR_FLAG}));
}

TEST_F(CanRaw, NoFiltersReceiveNothingAndTwoMatchesDeliverOnce) {
  Sock tx, none, both;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(none.set_filters({}), 0);
  ASSERT_EQ(both.set_filters({{0x100, 0x700}, {0x101, 0x7FF}}), 0);
  ASSERT_EQ(none.bind_to(vcan0), 0);
  ASSERT_EQ(both.bind_to(vcan0), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x101)), 0);
  EXPECT_EQ(count_frames(none.fd()), 0);
  EXPECT_EQ(count_frames(both.fd()), 1);
}

TEST_F(CanRaw, JoinedFiltersMustAllMatch) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.set_filters({{0x100, 0x700}, {0x001, 0x00F}}), 0);
  ASSERT_EQ(rx.set(SOL_CAN_RAW, CAN_RAW_JOIN_FILTERS, 1), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  for (canid_t id : {0x101U, 0x102U, 0x201U}) ASSERT_GT(send_frame(tx.fd(), frame(id)), 0);
  std::vector<canid_t> got;
  while (auto r = receive(rx.fd(), 100)) got.push_back(r->frame.can_id);
  EXPECT_EQ(got, (std::vector<canid_t>{0x101}));
}

// Filters that each take one id (canhil's delivery fence has 512 a socket):
// standard and extended apart, remote frames not, error frames by the error
// filter beside them.
TEST_F(CanRaw, ManySingleIdFiltersStandardExtendedAndErrors) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  constexpr canid_t kExact = CAN_EFF_FLAG | CAN_RTR_FLAG;
  std::vector<can_filter> filters;
  for (canid_t id = 0x100; id < 0x300; id += 2) filters.push_back({id, CAN_SFF_MASK | kExact});
  filters.push_back({0x7FF, CAN_SFF_MASK | kExact});
  filters.push_back({0x123 | CAN_EFF_FLAG, CAN_EFF_MASK | kExact});
  filters.push_back({0x1ABCDEF | CAN_EFF_FLAG, CAN_EFF_MASK | kExact});
  ASSERT_EQ(rx.set_filters(filters), 0);
  ASSERT_EQ(rx.set(SOL_CAN_RAW, CAN_RAW_ERR_FILTER, static_cast<can_err_mask_t>(CAN_ERR_BUSOFF)), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  const std::vector<canid_t> sent = {0x100U,
                                     0x101U,
                                     0x2FEU,
                                     0x300U,
                                     0x7FFU,
                                     0x100U | CAN_RTR_FLAG,
                                     0x100U | CAN_EFF_FLAG,
                                     0x123U,
                                     0x123U | CAN_EFF_FLAG,
                                     0x1ABCDEFU | CAN_EFF_FLAG,
                                     0x0ABCDEFU | CAN_EFF_FLAG,
                                     0x1ABCDEFU | CAN_EFF_FLAG | CAN_RTR_FLAG};
  for (const canid_t id : sent) ASSERT_GT(send_frame(tx.fd(), frame(id)), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0})), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, 0, 0, 0, 0, 0, 0, 0})), 0);
  std::vector<canid_t> got;
  while (auto r = receive(rx.fd(), 100)) got.push_back(r->frame.can_id);
  EXPECT_EQ(got, (std::vector<canid_t>{0x100, 0x2FE, 0x7FF, 0x123 | CAN_EFF_FLAG, 0x1ABCDEF | CAN_EFF_FLAG,
                                       CAN_ERR_FLAG | CAN_ERR_BUSOFF}));
}

TEST_F(CanRaw, ErrorFramesOnlyThroughTheErrorFilter) {
  Sock tx, plain, errors;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(errors.set(SOL_CAN_RAW, CAN_RAW_ERR_FILTER, static_cast<can_err_mask_t>(CAN_ERR_BUSOFF | CAN_ERR_FLAG)), 0);
  can_err_mask_t mask = 0;
  socklen_t len = sizeof mask;
  ASSERT_EQ(getsockopt(errors.fd(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, &len), 0);
  EXPECT_EQ(mask, static_cast<can_err_mask_t>(CAN_ERR_BUSOFF));  // the flag itself is masked off
  ASSERT_EQ(plain.bind_to(vcan0), 0);
  ASSERT_EQ(errors.bind_to(vcan0), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(CAN_ERR_FLAG | CAN_ERR_BUSOFF, {0, 0, 0, 0, 0, 0, 0, 0})), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(CAN_ERR_FLAG | CAN_ERR_CRTL, {0, 0, 0, 0, 0, 0, 0, 0})), 0);
  EXPECT_EQ(count_frames(plain.fd()), 0);
  const auto r = receive(errors.fd());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame.can_id, CAN_ERR_FLAG | CAN_ERR_BUSOFF);
  EXPECT_EQ(count_frames(errors.fd()), 0);
}

TEST_F(CanRaw, LoopbackAndOwnMessages) {
  Sock tx, rx;
  ASSERT_EQ(tx.bind_to(vcan0), 0);
  ASSERT_EQ(rx.bind_to(vcan0), 0);
  int v = -1;
  socklen_t len = sizeof v;
  ASSERT_EQ(getsockopt(tx.fd(), SOL_CAN_RAW, CAN_RAW_LOOPBACK, &v, &len), 0);
  EXPECT_EQ(v, 1);
  ASSERT_EQ(getsockopt(tx.fd(), SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &v, &len), 0);
  EXPECT_EQ(v, 0);
  // default: others hear it (a local frame: MSG_DONTROUTE), the sender does not
  ASSERT_GT(send_frame(tx.fd(), frame(0x10)), 0);
  const auto heard = receive(rx.fd());
  ASSERT_TRUE(heard);
  EXPECT_NE(heard->flags & MSG_DONTROUTE, 0);
  EXPECT_EQ(heard->flags & MSG_CONFIRM, 0);
  EXPECT_EQ(count_frames(tx.fd(), 50), 0);
  // own messages on: the sender gets its frame back, with MSG_CONFIRM
  ASSERT_EQ(tx.set(SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, 1), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x11)), 0);
  const auto own = receive(tx.fd());
  ASSERT_TRUE(own);
  EXPECT_EQ(own->frame.can_id, 0x11U);
  EXPECT_NE(own->flags & MSG_CONFIRM, 0);
  EXPECT_EQ(count_frames(rx.fd()), 1);
  // loopback off: on a virtual interface nobody hears it, the sender neither
  ASSERT_EQ(tx.set(SOL_CAN_RAW, CAN_RAW_LOOPBACK, 0), 0);
  ASSERT_GT(send_frame(tx.fd(), frame(0x12)), 0);
  EXPECT_EQ(count_frames(rx.fd()), 0);
  EXPECT_EQ(count_frames(tx.fd(), 50), 0);
}

TEST_F(CanRaw, OptionDefaultsAndTheFilterList) {
  Sock s;
  can_filter f[4] = {};
  socklen_t len = sizeof f;
  ASSERT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, f, &len), 0);
  ASSERT_EQ(len, static_cast<socklen_t>(sizeof(can_filter)));  // one filter that takes every frame
  EXPECT_EQ(f[0].can_id, 0U);
  EXPECT_EQ(f[0].can_mask, 0U);
  ASSERT_EQ(s.set_filters({{1, 2}, {3, 4}, {5, 6}}), 0);
  len = sizeof(can_filter);
  EXPECT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, f, &len), -1);
  EXPECT_EQ(errno, ERANGE);
  EXPECT_EQ(len, static_cast<socklen_t>(3 * sizeof(can_filter)));  // what it needs
  len = sizeof f;
  ASSERT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, f, &len), 0);
  EXPECT_EQ(len, static_cast<socklen_t>(3 * sizeof(can_filter)));
  EXPECT_EQ(f[2].can_id, 5U);
  int v = -1;
  len = sizeof v;
  for (int name : {CAN_RAW_FD_FRAMES, CAN_RAW_JOIN_FILTERS}) {
    ASSERT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, name, &v, &len), 0);
    EXPECT_EQ(v, 0);
  }
  ASSERT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &v, &len), 0);
  EXPECT_EQ(v, 0);
}

TEST_F(CanRaw, GarbageOptionsGetTheKernelsErrno) {
  Sock s;
  const char seven[7] = {};
  EXPECT_EQ(setsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, seven, sizeof seven), -1);
  EXPECT_EQ(errno, EINVAL);
  std::vector<can_filter> too_many(CAN_RAW_FILTER_MAX + 1);
  EXPECT_EQ(s.set_filters(too_many), -1);
  EXPECT_EQ(errno, EINVAL);
  EXPECT_EQ(setsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, bad_address(), 2 * sizeof(can_filter)), -1);
  EXPECT_EQ(errno, EFAULT);
  const short two = 1;
  EXPECT_EQ(setsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_LOOPBACK, &two, sizeof two), -1);
  EXPECT_EQ(errno, EINVAL);
  const int one = 1;
  EXPECT_EQ(setsockopt(s.fd(), SOL_CAN_RAW, 99, &one, sizeof one), -1);
  EXPECT_EQ(errno, ENOPROTOOPT);
  EXPECT_EQ(setsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &two, sizeof two), -1);
  EXPECT_EQ(errno, EINVAL);
  EXPECT_EQ(setsockopt(s.fd(), SOL_SOCKET, SO_TIMESTAMP, &two, sizeof two), -1);
  EXPECT_EQ(errno, EINVAL);
  int v = 0;
  EXPECT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, CAN_RAW_LOOPBACK, &v, static_cast<socklen_t*>(bad_address())), -1);
  EXPECT_EQ(errno, EFAULT);
  socklen_t len = sizeof v;
  EXPECT_EQ(getsockopt(s.fd(), SOL_CAN_RAW, 99, &v, &len), -1);
  EXPECT_EQ(errno, ENOPROTOOPT);
  // the socket still works
  ASSERT_EQ(s.bind_to(vcan0), 0);
  EXPECT_GT(send_frame(s.fd(), frame(1)), 0);
}

TEST_F(CanRaw, BadAddressesAndFramesAreRefused) {
  Sock s;
  const can_frame f = frame(0x1);
  EXPECT_EQ(send_frame(s.fd(), f), -1);  // not bound: no interface
  EXPECT_EQ(errno, ENXIO);
  sockaddr_can a{};
  a.can_family = AF_CAN;
  a.can_ifindex = 0x7fff0000;
  EXPECT_EQ(bind(s.fd(), reinterpret_cast<sockaddr*>(&a), sizeof a), -1);
  EXPECT_EQ(errno, ENODEV);
  a.can_ifindex = vcan0;
  EXPECT_EQ(bind(s.fd(), reinterpret_cast<sockaddr*>(&a), 4), -1);
  EXPECT_EQ(errno, EINVAL);
  a.can_family = AF_INET;
  EXPECT_EQ(bind(s.fd(), reinterpret_cast<sockaddr*>(&a), sizeof a), -1);
  EXPECT_EQ(errno, EINVAL);
  ASSERT_EQ(s.bind_to(vcan0), 0);
  EXPECT_EQ(write(s.fd(), &f, sizeof f - 1), -1);
  EXPECT_EQ(errno, EINVAL);
  canfd_frame fd{};
  EXPECT_EQ(write(s.fd(), &fd, sizeof fd), -1);  // an FD frame without CAN_RAW_FD_FRAMES
  EXPECT_EQ(errno, EINVAL);
  can_frame nine = frame(0x2);
  nine.len = 9;
  EXPECT_EQ(send_frame(s.fd(), nine), -1);
  EXPECT_EQ(errno, EINVAL);
  EXPECT_EQ(write(s.fd(), bad_address(), sizeof f), -1);
  EXPECT_EQ(errno, EFAULT);
  EXPECT_GT(send_frame(s.fd(), f), 0);
}
}  // namespace
}  // namespace canhil::test::can_raw
