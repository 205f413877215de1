// Results as JUnit XML and as a worker's JSON line (verdict/junit.hpp,
// verdict.hpp). The report is checked against Jenkins' schema with xmllint by
// tests/app/test_command_test.sh.
#include "canhil/verdict/junit.hpp"

#include <gtest/gtest.h>

#include <string>

namespace canhil::verdict {
namespace {

FileResult sample() {
  FileResult r;
  r.file = "tests/brake.toml";
  r.name = "brake <on> \"silence\"";
  r.virtual_s = 3;
  r.wall_s = 0.25;
  r.verdicts.push_back({"stops", "speed_below_m_s", 12, true, "below 0.05 m/s 600 ms after 'x'", ""});
  r.verdicts.push_back({"M6 & M7", "ftt_violations_at_most", 20, false, "3 violation(s)", "late at t=1.2 s\x01"});
  return r;
}

TEST(Junit, OneSuitePerFileOneCasePerExpectationFailuresWithTheirMessage) {
  FileResult broken;
  broken.file = "tests/bad.toml";
  broken.name = "bad";
  broken.error = "tests/bad.toml:3: test.scenario: missing";
  const std::string x = junit_xml({sample(), broken});
  EXPECT_NE(x.find("<testsuites name=\"canhil test\" tests=\"3\" failures=\"1\" errors=\"1\""), std::string::npos) << x;
  EXPECT_NE(x.find("<testsuite name=\"brake &lt;on&gt; &quot;silence&quot;\" tests=\"2\" failures=\"1\" errors=\"0\""),
            std::string::npos)
      << x;
  EXPECT_NE(x.find("<testcase name=\"stops\" classname=\"canhil.tests.brake\""), std::string::npos) << x;
  EXPECT_NE(x.find("<failure type=\"ftt_violations_at_most\" message=\"late at t=1.2 s?\">tests/brake.toml:20: late"),
            std::string::npos)
      << x;
  EXPECT_NE(x.find("<testcase name=\"M6 &amp; M7\""), std::string::npos);
  EXPECT_NE(x.find("<error type=\"setup\" message=\"tests/bad.toml:3: test.scenario: missing\">"), std::string::npos)
      << x;
  EXPECT_EQ(x.find('\x01'), std::string::npos) << "no character XML 1.0 cannot carry";
}

TEST(Junit, FilesOfOneNameInTwoFoldersAreTwoClasses) {
  FileResult a = sample(), b = sample();
  a.file = "tests/score.toml";
  b.file = "../team/tests/processes/score.toml";
  const std::string x = junit_xml({a, b});
  EXPECT_NE(x.find("classname=\"canhil.tests.score\""), std::string::npos) << x;
  EXPECT_NE(x.find("classname=\"canhil.team.tests.processes.score\""), std::string::npos) << x;
}

TEST(Junit, AWorkersLineGivesBackTheResult) {
  const FileResult r = sample();
  const FileResult back = from_json_line(to_json_line(r));
  EXPECT_EQ(back.file, r.file);
  EXPECT_EQ(back.name, r.name);
  EXPECT_DOUBLE_EQ(back.wall_s, r.wall_s);
  ASSERT_EQ(back.verdicts.size(), 2U);
  EXPECT_EQ(back.verdicts[1].message, r.verdicts[1].message);
  EXPECT_EQ(back.verdicts[1].line, 20);
  EXPECT_FALSE(back.verdicts[1].passed);
  EXPECT_EQ(to_json_line(r).find('\n'), std::string::npos) << "one line";
}

}  // namespace
}  // namespace canhil::verdict
