// The ring: first in, first out, through growth while its contents wrap
// around the end of the array, checked against std::deque on random work.
#include "canhil/base/ring.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <random>
#include <vector>

namespace canhil::base {
namespace {

TEST(Ring, GivesBackInOrderAcrossGrowthWhileWrapped) {
  Ring<int> ring;
  EXPECT_TRUE(ring.empty());
  for (int i = 0; i < 10; ++i) ring.push_back(i);
  for (int i = 0; i < 8; ++i) ring.pop_front();      // the head is now well inside the array
  for (int i = 10; i < 100; ++i) ring.push_back(i);  // wraps, then grows twice
  ASSERT_EQ(ring.size(), 92u);
  for (std::size_t i = 0; i < ring.size(); ++i) ASSERT_EQ(ring[i], static_cast<int>(i) + 8);
  for (int i = 8; i < 100; ++i) {
    ASSERT_EQ(ring.front(), i);
    ring.pop_front();
  }
  EXPECT_TRUE(ring.empty());
}

TEST(Ring, MovesInAndOut) {
  Ring<std::vector<int>> ring;
  std::vector<int> v{1, 2, 3};
  ring.push_back(std::move(v));
  ring.push_back(std::vector<int>{4});
  std::vector<int> out = std::move(ring.front());
  ring.pop_front();
  EXPECT_EQ(out, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(ring.front(), (std::vector<int>{4}));
}

TEST(Ring, DrainedItStartsAgainAtTheFirstSlot) {
  // A queue drained as it fills keeps using its first slots (they stay in the cache).
  Ring<int> ring;
  ring.push_back(0);
  const int* first = &ring.front();
  ring.pop_front();
  for (int i = 0; i < 100; ++i) {
    ring.push_back(i);
    ring.push_back(i + 1);
    ASSERT_EQ(&ring.front(), first) << "round " << i;
    ring.pop_front();
    ASSERT_EQ(&ring.front(), first + 1) << "round " << i;
    ASSERT_EQ(ring.front(), i + 1);
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
