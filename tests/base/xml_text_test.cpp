// Text put into an SVG element (base/xml_text.hpp), as the timing and match
// plots write names from the user's DBC and scenario.
#include "canhil/base/xml_text.hpp"

#include <gtest/gtest.h>

#include <string>

namespace canhil {
namespace {

TEST(XmlText, WritesTheCharactersOfMarkupAsEntities) {
  EXPECT_EQ(xml_text("M1<M2 & M3>M4"), "M1&lt;M2 &amp; M3&gt;M4");
  EXPECT_EQ(xml_text("<<&&>>"), "&lt;&lt;&amp;&amp;&gt;&gt;");
  EXPECT_EQ(xml_text("&amp;"), "&amp;amp;") << "an entity in a name is the name's text, not markup";
}

TEST(XmlText, LeavesEverythingElseAsItIs) {
  EXPECT_EQ(xml_text(""), "");
  EXPECT_EQ(xml_text("ODOM_OUT \"team\" 'new' \xC3\xA9quipe"), "ODOM_OUT \"team\" 'new' \xC3\xA9quipe");
  const std::string with_nul("a\0b", 3);
  EXPECT_EQ(xml_text(with_nul), with_nul);
}

}  // namespace
}  // namespace canhil
