#!/usr/bin/env bash
# build.sh [plain|sanitize|tsan] — configure and build one flavour into
# build/<flavour>, warnings as errors (the project's own builds; a default
# CMake configuration leaves them warnings).
#   plain     g++, Release (what a packager builds), tests and benchmarks
#   sanitize  clang, Debug, ASan + UBSan, and the libFuzzer targets
#   tsan      clang, RelWithDebInfo, ThreadSanitizer: the tests that start
#             threads or share memory between processes
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
flavour="${1:-plain}"
case "$flavour" in
  plain) args=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=g++ -DCMAKE_C_COMPILER=gcc) ;;
  sanitize) args=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang
                  -DCANHIL_SANITIZE=ON -DCANHIL_BUILD_BENCH=OFF) ;;
  tsan) args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang
              -DCANHIL_SANITIZE=thread -DCANHIL_BUILD_BENCH=OFF) ;;
  *) echo "build.sh: flavour must be plain, sanitize or tsan" >&2; exit 2 ;;
esac
cmake -S . -B "build/$flavour" -G Ninja -DCANHIL_WERROR=ON "${args[@]}" >/dev/null
cmake --build "build/$flavour"
