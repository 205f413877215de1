// The doorbell: rings kept per index across words, found in order, cleared
// one by one; a ring after a search is found by the next.
#include "canhil/can_nodes/doorbell.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace canhil::can_nodes {
namespace {

std::vector<std::size_t> rung(const Doorbell& bell) {
  std::vector<std::size_t> out;
  for (std::size_t i = bell.next(0); i != Doorbell::kNone; i = bell.next(i + 1)) out.push_back(i);
  return out;
}

TEST(Doorbell, FindsEveryRungIndexInOrderAcrossWords) {
  Doorbell bell;
  bell.resize(200);
  EXPECT_EQ(bell.next(0), Doorbell::kNone);
  for (std::size_t i : {130u, 0u, 64u, 63u, 199u}) bell.ring(i);
  EXPECT_EQ(rung(bell), (std::vector<std::size_t>{0, 63, 64, 130, 199}));
  EXPECT_EQ(bell.next(65), 130u);
  EXPECT_EQ(bell.next(200), Doorbell::kNone) << "past the end";
  bell.clear(64);
  bell.clear(0);
  EXPECT_FALSE(bell.rung(64));
  EXPECT_TRUE(bell.rung(63));
  EXPECT_EQ(rung(bell), (std::vector<std::size_t>{63, 130, 199}));
}

TEST(Doorbell, ARingAfterASearchIsFoundByTheNextAndGrowingKeepsRings) {
  Doorbell bell;
  bell.resize(10);
  bell.ring(3);
  const std::size_t first = bell.next(0);
  bell.ring(7);  // rung while the round is at 3
  EXPECT_EQ(bell.next(first + 1), 7u);
  bell.resize(100);
  bell.ring(90);
  EXPECT_EQ(rung(bell), (std::vector<std::size_t>{3, 7, 90}));
}

}  // namespace
}  // namespace canhil::can_nodes
