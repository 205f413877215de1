// bus_latency — a CAN bus's frame delivery latency and lossless rate, next to
// a bare AF_UNIX datagram socket pair measured in the same run (the ratio is
// the figure; the machine's speed cancels). Runs on any SocketCAN bus:
//   canhil bus exec --ifaces vcan0 -- build/plain/bench/bus_latency     the user-space bus
//   vcan_setup/with-vcan.sh -- build/plain/bench/bus_latency            the kernel's vcan
// Latency: half a ping-pong's round trip between two processes, each blocked
// in read() until the other's frame arrives (p50 and p99 of 20 000). Rate: one
// process writes 200 000 frames as fast as write() takes them (cangen -g 0),
// another reads them; frames per second when every one arrived.
// Targets (issue 32): p99 within 3x of the socket pair, rate at least 0.5 of it.
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

double now_s() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_nsec) * 1e-9;
}

[[noreturn]] void die(const char* what) {
  std::fprintf(stderr, "bus_latency: %s: %s\n", what, std::strerror(errno));
  std::exit(2);
}

int can_socket(int ifindex, canid_t only) {
  const int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (s < 0) die("socket(PF_CAN) (run it on a bus: canhil bus exec -- ...)");
  const can_filter f{only, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG};
  setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, &f, sizeof f);
  sockaddr_can a{};
  a.can_family = AF_CAN;
  a.can_ifindex = ifindex;
  if (bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) die("bind");
  return s;
}

struct Pair {
  int a;  // the measuring side
  int b;  // the echoing (or reading) side
};

/// Round trips of a 16-byte message between the two ends (b echoes in a child process); one-way times in µs.
std::vector<double> ping_pong(const Pair& p, int rounds, bool can) {
  const pid_t child = fork();
  if (child == 0) {
    can_frame f{};
    for (int k = 0; k < rounds + 100; ++k) {
      if (read(p.b, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) _exit(1);
      if (can) f.can_id = 0x101;
      if (write(p.b, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) _exit(1);
    }
    _exit(0);
  }
  std::vector<double> one_way;
  one_way.reserve(static_cast<std::size_t>(rounds));
  can_frame f{};
  f.can_id = 0x100;
  f.len = 8;
  for (int k = 0; k < rounds + 100; ++k) {
    const double t0 = now_s();
    if (write(p.a, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) die("write");
    if (read(p.a, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) die("read");
    f.can_id = 0x100;
    if (k >= 100) one_way.push_back((now_s() - t0) * 1e6 / 2.0);  // the first 100 warm up
  }
  waitpid(child, nullptr, 0);
  std::sort(one_way.begin(), one_way.end());
  return one_way;
}

/// Frames per second from a.write as fast as it takes them to b.read; 0 when any was lost.
double rate(const Pair& p, int frames) {
  int ready[2];
  if (pipe(ready) != 0) die("pipe");
  const pid_t child = fork();
  if (child == 0) {
    can_frame f{};
    int got = 0;
    const char go = 1;
    if (write(ready[1], &go, 1) != 1) _exit(1);
    for (; got < frames; ++got) {
      if (read(p.b, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) break;
      if (f.data[0] == 0xFF) break;  // the end marker: frames were lost before it
    }
    _exit(got == frames ? 0 : 1);
  }
  char go = 0;
  if (read(ready[0], &go, 1) != 1) die("read");
  can_frame f{};
  f.can_id = 0x100;
  f.len = 8;
  const double t0 = now_s();
  for (int k = 0; k < frames; ++k) {
    while (write(p.a, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) {
      if (errno != ENOBUFS && errno != EAGAIN) die("write");
      usleep(100);
    }
  }
  int status = 0;
  // A receiver that lost frames waits for more: an end marker tells it to stop.
  const pid_t done = waitpid(child, &status, WNOHANG);
  if (done == 0) {
    usleep(300000);
    if (waitpid(child, &status, WNOHANG) == 0) {
      f.data[0] = 0xFF;
      if (write(p.a, &f, sizeof f) < 0) die("write");
      waitpid(child, &status, 0);
    }
  }
  const double seconds = now_s() - t0;
  close(ready[0]);
  close(ready[1]);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? frames / seconds : 0.0;
}

int whole(const char* text) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v <= 0 || v > 100000000) {
    std::fprintf(stderr, "bus_latency: %s is not a positive whole number\n", text);
    std::exit(2);
  }
  return static_cast<int>(v);
}

double at(const std::vector<double>& sorted, double q) {
  return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1))];
}

}  // namespace

int main(int argc, char** argv) {
  std::string iface = "vcan0";
  int rounds = 20000;
  int frames = 200000;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string o = argv[k];
    if (o == "--iface")
      iface = argv[k + 1];
    else if (o == "--round-trips")
      rounds = whole(argv[k + 1]);
    else if (o == "--frames")
      frames = whole(argv[k + 1]);
    else {
      std::fprintf(stderr, "usage: bus_latency [--iface vcan0] [--round-trips 20000] [--frames 200000]\n");
      return 2;
    }
  }
  const int index = static_cast<int>(if_nametoindex(iface.c_str()));
  if (index == 0) die(("interface " + iface).c_str());

  int sv[2];
  if (socketpair(AF_UNIX, SOCK_DGRAM, 0, sv) != 0) die("socketpair");
  const Pair unix_pair{sv[0], sv[1]};
  const Pair can_pair{can_socket(index, 0x101), can_socket(index, 0x100)};

  const std::vector<double> ref = ping_pong(unix_pair, rounds, false);
  const std::vector<double> bus = ping_pong(can_pair, rounds, true);
  const double ref_rate = rate(unix_pair, frames);
  const double bus_rate = rate(can_pair, frames);

  std::printf("bus_latency on %s (index %d), %d round trips, %d frames\n", iface.c_str(), index, rounds, frames);
  std::printf("  AF_UNIX datagram pair:  one way p50 %7.1f us  p99 %7.1f us   rate %9.0f frames/s\n", at(ref, 0.5),
              at(ref, 0.99), ref_rate);
  std::printf("  CAN_RAW on %-6s       one way p50 %7.1f us  p99 %7.1f us   rate %9.0f frames/s%s\n", iface.c_str(),
              at(bus, 0.5), at(bus, 0.99), bus_rate, bus_rate == 0.0 ? " (frames lost)" : "");
  const double p99_ratio = at(bus, 0.99) / at(ref, 0.99);
  const double rate_ratio = bus_rate / ref_rate;
  std::printf("  p99 latency, bus / pair: %.2fx  target <= 3x: %s\n", p99_ratio, p99_ratio <= 3.0 ? "met" : "MISSED");
  std::printf("  lossless rate, bus / pair: %.2f  target >= 0.5: %s\n", rate_ratio,
              rate_ratio >= 0.5 ? "met" : "MISSED");
  return p99_ratio <= 3.0 && rate_ratio >= 0.5 ? 0 : 1;
}
