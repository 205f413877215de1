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
#include <system_error>

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

}  // namespace canhil
