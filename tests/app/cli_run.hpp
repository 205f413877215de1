// tests/app/cli_run.hpp — the canhil command run from the source folder, its
// output (stdout and stderr together) and exit status, for the CLI tests.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "support/test_paths.hpp"

namespace canhil::test {

struct CliRun {
  int status;
  std::string out;  // stdout and stderr together
};

inline CliRun canhil(const std::string& args, const std::string& env = "") {
  const std::string cmd =
      "cd " + source_dir() + " && " + env + (env.empty() ? "" : " ") + canhil_binary() + " " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  CliRun r{-1, ""};
  if (p == nullptr) return r;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p) != nullptr) r.out += buf;
  const int raw = pclose(p);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

inline bool has(const CliRun& r, const std::string& text) { return r.out.find(text) != std::string::npos; }

}  // namespace canhil::test
