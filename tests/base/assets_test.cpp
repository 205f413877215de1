// Where shipped files are found (base/assets.hpp): the environment's path as
// given, else an installed copy relative to the running program, else the
// build tree's.
#include "canhil/base/assets.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace canhil {
namespace {

namespace fs = std::filesystem;

TEST(Assets, TheEnvironmentNamesAPathWhenSetAndNotEmpty) {
  unsetenv("CANHIL_ASSETS_TEST");
  EXPECT_FALSE(path_from_environment("CANHIL_ASSETS_TEST").has_value());
  setenv("CANHIL_ASSETS_TEST", "", 1);
  EXPECT_FALSE(path_from_environment("CANHIL_ASSETS_TEST").has_value()) << "empty is unset";
  setenv("CANHIL_ASSETS_TEST", "relative/file.dbc", 1);
  EXPECT_EQ(path_from_environment("CANHIL_ASSETS_TEST"), fs::path("relative/file.dbc")) << "taken as given";
  unsetenv("CANHIL_ASSETS_TEST");
}

TEST(Assets, AnInstalledCopyBesideTheProgramElseTheBuiltOne) {
  const fs::path folder = program_folder();
  ASSERT_FALSE(folder.empty());
  EXPECT_TRUE(fs::exists(folder / fs::path("base_tests"))) << folder << ": this test program's folder";
  const std::string probe = "canhil_assets_probe_" + std::to_string(getpid());
  EXPECT_EQ(installed_or_built({probe}, "/built/copy"), fs::path("/built/copy")) << "nothing installed";
  std::ofstream(folder / probe) << "x";
  EXPECT_EQ(installed_or_built({"../no/such/" + probe, probe}, "/built/copy"), folder / probe) << "the first there";
  EXPECT_EQ(installed_or_built({probe}, "/built/copy", [](const fs::path&) { return false; }), fs::path("/built/copy"))
      << "present but not usable";
  fs::remove(folder / probe);
}

}  // namespace
}  // namespace canhil
