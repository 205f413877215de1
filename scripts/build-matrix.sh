#!/usr/bin/env bash
# build-matrix.sh — builds canhil with every CMake build type and both of
# Debian 12's compilers, warnings as errors, into build/matrix/COMPILER-TYPE.
# Not part of CI (eight full builds); run it before changing warnings or
# compiler-sensitive code:
#   scripts/build-matrix.sh                       # all eight
#   scripts/build-matrix.sh gcc:Release clang:MinSizeRel
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
combos=("$@")
if [[ ${#combos[@]} -eq 0 ]]; then
  for c in gcc clang; do
    for t in Debug Release RelWithDebInfo MinSizeRel; do combos+=("$c:$t"); done
  done
fi
failed=()
for combo in "${combos[@]}"; do
  compiler=${combo%%:*}
  type=${combo#*:}
  case "$compiler" in
    gcc) cc=gcc cxx=g++ ;;
    clang) cc=clang cxx=clang++ ;;
    *) echo "build-matrix: compiler must be gcc or clang, got $compiler" >&2; exit 2 ;;
  esac
  dir="build/matrix/$compiler-$type"
  echo "== $compiler $type ($dir)"
  if cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE="$type" -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx" \
       -DCANHIL_WERROR=ON >/dev/null && cmake --build "$dir" >"$dir.log" 2>&1; then
    echo "   clean"
  else
    echo "   FAILED (log: $dir.log)"
    failed+=("$combo")
  fi
done
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "build-matrix: ${#failed[@]} failed: ${failed[*]}" >&2
  exit 1
fi
echo "build-matrix: all ${#combos[@]} clean"
