#!/usr/bin/env bash
# build.sh [plain|sanitize] — configure and build one flavour into build/<flavour>.
#   plain     g++, RelWithDebInfo
#   sanitize  clang, ASan + UBSan, and the libFuzzer targets
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
flavour="${1:-plain}"
case "$flavour" in
  plain) args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=g++ -DCMAKE_C_COMPILER=gcc) ;;
  sanitize) args=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang
                  -DCANHIL_SANITIZE=ON -DCANHIL_BUILD_BENCH=OFF) ;;
  *) echo "build.sh: flavour must be plain or sanitize" >&2; exit 2 ;;
esac
cmake -S . -B "build/$flavour" -G Ninja "${args[@]}" >/dev/null
cmake --build "build/$flavour"
