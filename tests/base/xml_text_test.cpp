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

TEST(XmlEscaped, AnyTextMakesAWellFormedAttributeOrContent) {
  EXPECT_EQ(xml_escaped("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
  EXPECT_EQ(xml_escaped("tab\tnl\ncr\r"), "tab\tnl\ncr\r") << "the three controls XML 1.0 carries";
  const std::string controls("x\0y\x01z\x1B", 6);
  EXPECT_EQ(xml_escaped(controls), "x?y?z?") << "no XML 1.0 character: replaced, never written";
  EXPECT_EQ(xml_escaped("\xC3\xA9quipe \xE2\x82\xAC \xF0\x9F\x98\x80"), "\xC3\xA9quipe \xE2\x82\xAC \xF0\x9F\x98\x80")
      << "valid UTF-8 kept whole";
  EXPECT_EQ(xml_escaped("bad \xC3 end \xFF \xE2\x82"), "bad ? end ? ??") << "broken sequences replaced byte by byte";
}

}  // namespace
}  // namespace canhil
