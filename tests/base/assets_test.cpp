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

TEST(Assets, AFileThatMustBeThereIsTheVariablesElseInstalledElseBuiltElseANamedError) {
  const fs::path folder = program_folder();
  const std::string probe = "canhil_asset_probe_" + std::to_string(getpid());
  const fs::path built = fs::temp_directory_path() / probe;
  unsetenv("CANHIL_ASSETS_TEST");
  try {
    find_asset("CANHIL_ASSETS_TEST", "the probe", {probe}, built, "probe_target");
    ADD_FAILURE() << "nothing anywhere: an error";
  } catch (const SetupError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the probe " + probe + " is not at " + (folder / probe).string()), std::string::npos) << what;
    EXPECT_NE(what.find(built.string()), std::string::npos) << what;
    EXPECT_NE(what.find("build it (target probe_target) or set CANHIL_ASSETS_TEST="), std::string::npos) << what;
  }
  std::ofstream(built) << "x";
  EXPECT_EQ(find_asset("CANHIL_ASSETS_TEST", "the probe", {probe}, built, "probe_target"), built);
  std::ofstream(folder / probe) << "x";
  EXPECT_EQ(find_asset("CANHIL_ASSETS_TEST", "the probe", {probe}, built, "probe_target"), folder / probe)
      << "the installed copy first";
  setenv("CANHIL_ASSETS_TEST", "/no/such/file", 1);
  EXPECT_THROW(find_asset("CANHIL_ASSETS_TEST", "the probe", {probe}, built, "probe_target"), SetupError)
      << "a variable naming nothing is an error, not a fallback";
  setenv("CANHIL_ASSETS_TEST", built.c_str(), 1);
  EXPECT_EQ(find_asset("CANHIL_ASSETS_TEST", "the probe", {probe}, built, "probe_target"), built);
  unsetenv("CANHIL_ASSETS_TEST");
  fs::remove(folder / probe);
  fs::remove(built);
}

}  // namespace
}  // namespace canhil
