// CAN_RAW as the kernel documents it (Documentation/networking/can.rst), one
// test per point, for two backends with the same expectations: this program,
// built once, runs against the kernel's vcan in the VM runner
// (vcan.can_raw_conformance) and against the user-space bus natively, under
// `canhil bus exec` (userbus.can_raw_conformance). Interfaces vcan0 and vcan1,
// both up. A difference between the backends fails here.
//
// Started with CANHIL_CONFORMANCE_EXEC_FD=N, the program is the far side of
// the exec test instead: it reads one frame from descriptor N (inherited
// across exec) and writes it back with its id plus one.
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
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
#include <time.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <optional>
#include <string>
#include <vector>

namespace {

int index_of(const char* name) { return static_cast<int>(if_nametoindex(name)); }

/// `name` into an interface request.
void name_into(ifreq& r, const char* name) { std::snprintf(r.ifr_name, IFNAMSIZ, "%s", name); }

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

can_frame frame(canid_t id, std::initializer_list<int> data = {}) {
  can_frame f{};
  f.can_id = id;
  f.len = static_cast<std::uint8_t>(data.size());
  int k = 0;
  for (int d : data) f.data[k++] = static_cast<std::uint8_t>(d);
  return f;
}

bool readable(int fd, int timeout_ms) {
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
std::optional<Received> receive(int fd, int timeout_ms = 200, std::size_t control_room = 0) {
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
int count_frames(int fd, int quiet_ms = 100) {
  int n = 0;
  while (receive(fd, quiet_ms)) ++n;
  return n;
}

ssize_t send_frame(int fd, const can_frame& f) { return write(fd, &f, sizeof f); }

/// An address no program may read or write (the first page), as the compiler cannot see it.
void* bad_address() {
  static volatile std::uintptr_t at = 8;
  return reinterpret_cast<void*>(at);  // NOLINT(performance-no-int-to-ptr): an address that is no object's, on purpose
}

constexpr std::int64_t kSkew = 2'000'000;  // ns

std::int64_t now_ns() {
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

int main(int argc, char** argv) {
  if (const char* fd = std::getenv("CANHIL_CONFORMANCE_EXEC_FD"))
    return exec_child(static_cast<int>(std::strtol(fd, nullptr, 10)));
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
