// The floor under every hand-over of the lockstep (round_trip.hpp).
#include "canhil/lockstep/round_trip.hpp"

#include <linux/futex.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <ctime>
#include <new>

#include "canhil/lockstep/board.hpp"
#include "canhil/lockstep/conductor.hpp"

namespace canhil::lockstep {
namespace {

// Waits until `word` is `wanted` (it is `other` until then), looking every
// 100 ms whether `partner_gone()` says there is nobody left to change it.
// False when there is not.
template <typename Gone>
bool await(std::atomic<std::uint32_t>* word, std::uint32_t wanted, std::uint32_t other, Gone&& partner_gone) {
  const timespec look{0, 100'000'000};
  while (word->load(std::memory_order_acquire) != wanted) {
    if (futex(word, FUTEX_WAIT, other, &look) < 0 && errno == ETIMEDOUT && partner_gone()) return false;
  }
  return true;
}

}  // namespace

std::optional<Nanos> bare_round_trip(int rounds) {
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free, "a futex word shared between processes");
  void* shared =
      ::mmap(nullptr, sizeof(std::atomic<std::uint32_t>), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (shared == MAP_FAILED) return std::nullopt;
  auto* turn = new (shared) std::atomic<std::uint32_t>(0);  // 0: this process's turn, 1: the child's
  const pid_t parent = ::getpid();
  const pid_t child = ::fork();
  if (child == 0) {
    // The child never outlives the bench (Ctrl-C, a crash): it goes with its parent.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    const auto parent_gone = [&] { return ::getppid() != parent; };
    for (int i = 0; i < rounds; ++i) {  // (the parent is looked for only when a wait times out)
      if (!await(turn, 1, 0, parent_gone)) break;
      turn->store(0, std::memory_order_release);
      futex(turn, FUTEX_WAKE, 1);
    }
    ::_exit(0);
  }
  std::optional<Nanos> mean;
  if (child > 0) {
    bool reaped = false;
    const auto child_gone = [&] {
      reaped = ::waitpid(child, nullptr, WNOHANG) == child;
      return reaped;
    };
    const Nanos start = lockstep::wall_clock();
    bool answered = true;
    for (int i = 0; i < rounds && answered; ++i) {
      turn->store(1, std::memory_order_release);
      futex(turn, FUTEX_WAKE, 1);
      answered = await(turn, 0, 1, child_gone);
    }
    if (answered) mean = (lockstep::wall_clock() - start) / rounds;  // a child that died measured nothing
    if (!reaped) {
      while (::waitpid(child, nullptr, 0) < 0 && errno == EINTR) {
      }
    }
  }
  ::munmap(shared, sizeof(std::atomic<std::uint32_t>));
  return mean;
}

}  // namespace canhil::lockstep
