// The nearest known word to a mistyped one (base/spelling.hpp), as every
// configuration's "did you mean" uses it.
#include "canhil/base/spelling.hpp"

#include <gtest/gtest.h>

#include <array>
#include <set>
#include <string>
#include <string_view>

namespace canhil {
namespace {

TEST(Spelling, EditDistanceCountsInsertionsDeletionsAndSubstitutions) {
  EXPECT_EQ(edit_distance("", ""), 0u);
  EXPECT_EQ(edit_distance("seed", "seed"), 0u);
  EXPECT_EQ(edit_distance("duratoin_s", "duration_s"), 2u) << "a swap is two substitutions";
  EXPECT_EQ(edit_distance("kick", "kicks"), 1u);
  EXPECT_EQ(edit_distance("kicks", "kick"), 1u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
}

TEST(Spelling, TheNearestWithinThreeEditsTheFirstOfEquals) {
  const std::array<std::string_view, 3> keys{"length_m", "width_m", "margin_m"};
  EXPECT_EQ(nearest_word("lenght_m", keys), "length_m");
  EXPECT_EQ(nearest_word("nothing_like_it", keys), "");
  EXPECT_EQ(nearest_word("xidth_m", keys, 0), "") << "the limit holds";
  const std::set<std::string> known{"aa", "ab"};  // equally near "ac": the first in order
  EXPECT_EQ(nearest_word("ac", known), "aa");
}

}  // namespace
}  // namespace canhil
