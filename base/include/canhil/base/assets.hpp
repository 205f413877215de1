// canhil/base/assets.hpp — where the files canhil ships are found, by one
// rule for all of them (the message set, the layouts, the scenarios, the
// viewer's page, the time shim): a variable of the environment names it,
// taken as given; else an installed copy, found from the running program's
// folder (bin/ beside share/canhil/ and lib/); else the copy in the build or
// source tree, whose path is compiled in.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <optional>
#include <string>
#include <system_error>

#include "canhil/base/setup_error.hpp"

namespace canhil {

/// The folder of the running program (/proc/self/exe), or an empty path when
/// the system cannot say.
inline std::filesystem::path program_folder() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path();
}

/// Environment variable `name` as a path, when it is set and not empty.
inline std::optional<std::filesystem::path> path_from_environment(const char* name) {
  const char* value = std::getenv(name);
  if (value == nullptr || *value == '\0') return std::nullopt;
  return std::filesystem::path(value);
}

/// The first of `installed` (paths relative to the running program's folder,
/// such as "../share/canhil/layouts") that `usable` accepts (by default: it
/// exists), else `built`.
inline std::filesystem::path installed_or_built(std::initializer_list<std::filesystem::path> installed,
                                                const std::filesystem::path& built,
                                                const std::function<bool(const std::filesystem::path&)>& usable = {}) {
  const std::filesystem::path folder = program_folder();
  if (!folder.empty()) {
    for (const std::filesystem::path& relative : installed) {
      std::filesystem::path p = (folder / relative).lexically_normal();
      std::error_code ec;
      if (usable ? usable(p) : std::filesystem::exists(p, ec)) return p;
    }
  }
  return built;
}

/// A file that must be there, by the same rule: $`variable` when set (it must
/// exist: the user named it), else the first of `installed` (relative to the
/// running program's folder) that exists, else `built` when it exists.
/// SetupError naming the places looked at, the build target that makes the
/// file (`target`) and the variable to set; `what` names the file in it ("the
/// time shim"). For the libraries canhil preloads (the time shim, the bus's
/// preload), whose copy must exist to be used.
inline std::filesystem::path find_asset(const char* variable, const char* what,
                                        std::initializer_list<std::filesystem::path> installed,
                                        const std::filesystem::path& built, const char* target) {
  if (const auto given = path_from_environment(variable)) {
    std::error_code ec;
    if (!std::filesystem::exists(*given, ec))
      throw SetupError(std::string(variable) + "=" + given->string() + ": no such file");
    return std::filesystem::absolute(*given, ec);
  }
  std::filesystem::path found = installed_or_built(installed, built);
  std::error_code ec;
  if (std::filesystem::exists(found, ec)) return found;
  std::string looked;
  const std::filesystem::path folder = program_folder();
  for (const std::filesystem::path& relative : installed)
    looked += (folder / relative).lexically_normal().string() + ", ";
  looked += built.string();
  throw SetupError(std::string(what) + " " + built.filename().string() + " is not at " + looked +
                   ": build it (target " + target + ") or set " + variable + "=/path/to/" + built.filename().string());
}

}  // namespace canhil
