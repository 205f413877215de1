// `canhil timing --analyse` end to end: the shipped set's analysis and what-if,
// a trace against it, a set that does not fit, a malformed --add, --json and
// --svg.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

#include "cli_run.hpp"
#include "support/test_paths.hpp"

namespace {

using canhil::test::canhil;
using canhil::test::CliRun;
using canhil::test::has;

TEST(CanhilTimingAnalyse, TheShippedSetIsSchedulableAndItsSampleTraceInsideEveryBound) {
  const CliRun r = canhil("timing --analyse frames/samples/one_robot.log");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(has(r, "FTT-CAN message set: EC 10000 us, 1000000 bit/s")) << r.out;
  EXPECT_TRUE(has(r, "worst EC 0: 1370.0 us of the 9730.0 us allowed")) << r.out;
  EXPECT_TRUE(has(r, "rate-monotonic test of Almeida, Pedreiras & Fonseca")) << r.out;
  EXPECT_TRUE(has(r, "shortest EC (one that divides every synchronous period): 2000 us")) << r.out;
  EXPECT_TRUE(has(r, "M1             22 more copies fit; limited by the free FTT indices")) << r.out;
  EXPECT_TRUE(has(r, "Schedulable: every message meets its deadline")) << r.out;
  EXPECT_TRUE(has(r, "The trace against the analysis (183 frames)")) << r.out;
  EXPECT_TRUE(has(r, "Every observation is inside its bound")) << r.out;
}

TEST(CanhilTimingAnalyse, ASetThatDoesNotFitExitsOneNamingWhoMissesAndByHowMuch) {
  const CliRun r = canhil("timing --analyse --no-what-if --bit-rate 150000 --add 'Big 0x0F0 8 10 sync'");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_TRUE(has(r, "NOT schedulable")) << r.out;
  EXPECT_TRUE(has(r, "the FTT master: the FTT schedule does not fit the 10000 us elementary cycle")) << r.out;
  EXPECT_TRUE(has(r, "Big misses by 1720.0 us")) << r.out;
}

TEST(CanhilTimingAnalyse, AMalformedAddNamesTheFieldAndAnalysesNothing) {
  const CliRun r = canhil("timing --analyse --add 'Sonar 0x180 9 20 sync'");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_TRUE(has(r, "--add \"Sonar 0x180 9 20 sync\": DLC: \"9\" is not a classic CAN length")) << r.out;
  EXPECT_FALSE(has(r, "Frame times")) << r.out;
}

TEST(CanhilTimingAnalyse, JsonAndSvgCarryTheSameVerdict) {
  const std::string svg = canhil::test::build_dir() + "/cli_timing_analyse.svg";
  const CliRun r = canhil("timing --analyse --json --no-what-if --svg " + svg + " frames/samples/one_robot.log");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.rfind("{\"analysis\":{\"ftt\":true,", 0), 0u) << r.out;
  EXPECT_TRUE(has(r, "\"schedulable\":true,\"misses\":[]}")) << r.out;
  EXPECT_TRUE(has(r, ",\"trace\":{\"frames\":183,\"violation_count\":0,")) << r.out;
  std::ifstream in(svg);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.rfind("<svg ", 0), 0u);
  EXPECT_NE(text.find("EC 0  worst"), std::string::npos) << "the worst EC marked";
  EXPECT_NE(text.find("<title>M9</title>"), std::string::npos) << "each synchronous frame a bar";
}

TEST(CanhilTimingAnalyse, TheBenchmarkPrintsBothSetsAgainstTheTarget) {
  // Wall-clock: printed, never judged here (the exit status says met or missed).
  const CliRun r = canhil("bench --part analyse");
  EXPECT_TRUE(r.status == 0 || r.status == 1) << r.out;
  EXPECT_TRUE(has(r, "FTT-CAN: TM, 31 synchronous, 168 sporadic:")) << r.out;
  EXPECT_TRUE(has(r, "native CAN: 100 periodic, 100 sporadic:")) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 3) << r.out;
  EXPECT_TRUE(has(r, "; schedulable)  target <= 50 ms:")) << "the sets are meant to fit\n" << r.out;
}

}  // namespace
