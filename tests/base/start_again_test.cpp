// LD_PRELOAD composed the one way: the library first, the rest after it, the
// library never twice, wherever it already was in the list.
#include "canhil/base/start_again.hpp"

#include <gtest/gtest.h>

namespace canhil {
namespace {

TEST(PreloadList, TheLibraryFirstAndNeverTwice) {
  EXPECT_EQ(preload_list("/l/bus.so", ""), "/l/bus.so");
  EXPECT_EQ(preload_list("/l/bus.so", "/t/team.so"), "/l/bus.so:/t/team.so");
  EXPECT_EQ(preload_list("/l/bus.so", "/l/bus.so"), "/l/bus.so");
  EXPECT_EQ(preload_list("/l/bus.so", "/l/bus.so:/t/team.so"), "/l/bus.so:/t/team.so");
  EXPECT_EQ(preload_list("/l/bus.so", "/t/team.so:/l/bus.so"), "/t/team.so:/l/bus.so") << "there already: kept";
  EXPECT_EQ(preload_list("/l/bus.so", "/a.so:/l/bus.so:/b.so"), "/a.so:/l/bus.so:/b.so");
  EXPECT_EQ(preload_list("/l/bus.so", "/x/l/bus.so"), "/l/bus.so:/x/l/bus.so") << "another path is another library";
}

TEST(OwnArguments, AreThisProcesssCommandLine) {
  const std::vector<std::string> args = own_arguments();
  ASSERT_FALSE(args.empty());
  EXPECT_NE(args[0].find("base_tests"), std::string::npos) << args[0];
}

}  // namespace
}  // namespace canhil
