// What a preloaded library, or a program with one in front of its calls,
// looks up of libc's (base/preload.hpp).
#include "canhil/base/preload.hpp"

#include <gtest/gtest.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <ctime>

namespace {

TEST(Preload, LibcSymbolIsLibcsOwnAndNoneForWhatLibcLacks) {
  using ClockGettime = int (*)(clockid_t, timespec*);
  const auto libc_clock = canhil::preload::libc_symbol<ClockGettime>("clock_gettime");
  ASSERT_NE(libc_clock, nullptr);
  // The same clock as the system call's: read around one of its readings.
  timespec before{};
  timespec through_libc{};
  timespec after{};
  syscall(SYS_clock_gettime, CLOCK_MONOTONIC, &before);
  ASSERT_EQ(libc_clock(CLOCK_MONOTONIC, &through_libc), 0);
  syscall(SYS_clock_gettime, CLOCK_MONOTONIC, &after);
  const auto ns = [](const timespec& t) { return t.tv_sec * 1'000'000'000LL + t.tv_nsec; };
  EXPECT_LE(ns(before), ns(through_libc));
  EXPECT_LE(ns(through_libc), ns(after));
  EXPECT_EQ(canhil::preload::libc_symbol<ClockGettime>("canhil_no_such_call"), nullptr);
}

TEST(Preload, RealMonotonicIsTheMachinesClock) {
  timespec before{};
  timespec after{};
  syscall(SYS_clock_gettime, CLOCK_MONOTONIC, &before);
  const timespec real = canhil::preload::real_monotonic();
  syscall(SYS_clock_gettime, CLOCK_MONOTONIC, &after);
  const auto ns = [](const timespec& t) { return t.tv_sec * 1'000'000'000LL + t.tv_nsec; };
  EXPECT_LE(ns(before), ns(real));
  EXPECT_LE(ns(real), ns(after));
}

}  // namespace
