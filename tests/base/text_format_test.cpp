// printf's formats into a whole std::string (base/text_format.hpp): short and
// long texts, as the verdicts and the solver's reports build them.
#include "canhil/base/text_format.hpp"

#include <gtest/gtest.h>

#include <string>

namespace canhil {
namespace {

TEST(FormatText, ShortAndLongTextsComeWhole) {
  EXPECT_EQ(format_text("%.2f m at %d s", 0.5, 3), "0.50 m at 3 s");
  EXPECT_EQ(format_text("%s", ""), "");
  const std::string name(1000, 'x');  // longer than any fixed buffer a message once had (512)
  const std::string text = format_text("'%s' ended at t = %.3f s", name.c_str(), 1.0);
  EXPECT_EQ(text, "'" + name + "' ended at t = 1.000 s");
}

}  // namespace
}  // namespace canhil
