// The ring: first in, first out, through growth while its contents wrap
// around the end of the array, checked against std::deque on random work.
#include "canhil/base/ring.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <random>

namespace canhil::base {
namespace {

TEST(Ring, GivesBackInOrderAcrossGrowthWhileWrapped) {
  Ring<int> ring;
  EXPECT_TRUE(ring.empty());
  for (int i = 0; i < 10; ++i) ring.push_back(i);
  for (int i = 0; i < 8; ++i) ring.pop_front();      // the head is now well inside the array
  for (int i = 10; i < 100; ++i) ring.push_back(i);  // wraps, then grows twice
  ASSERT_EQ(ring.size(), 92u);
  for (int i = 8; i < 100; ++i) {
    ASSERT_EQ(ring.front(), i);
    ring.pop_front();
  }
  EXPECT_TRUE(ring.empty());
}

TEST(Ring, AgreesWithADequeOnRandomPushesAndPops) {
  Ring<std::uint64_t> ring;
  std::deque<std::uint64_t> reference;
  std::mt19937_64 rng(7);
  for (int step = 0; step < 200'000; ++step) {
    const bool push = reference.empty() || rng() % 100 < (step < 100'000 ? 55u : 45u);
    if (push) {
      const std::uint64_t v = rng();
      ring.push_back(v);
      reference.push_back(v);
    } else {
      ASSERT_EQ(ring.front(), reference.front()) << "step " << step;
      ring.pop_front();
      reference.pop_front();
    }
    ASSERT_EQ(ring.size(), reference.size());
  }
}

}  // namespace
}  // namespace canhil::base
