#!/usr/bin/env bash
# build.sh [plain|sanitize|tsan|lint] [TARGET...] — configure and build one flavour
# into build/<flavour>, warnings as errors (the project's own builds; a default
# CMake configuration leaves them warnings). With targets, only those and what
# they need (scripts/main.sh builds the three programs it runs).
#   plain     g++, Release at -O2 (the level Debian builds its packages at;
#             -O3 took 13 % more compile CPU for 2 % of run time), tests and
#             benchmarks; the test programs' own code (tests/) at -O1: the
#             build from scratch 127 -> 108 s, the tests' time unchanged
#             (CANHIL_TEST_OPT sets another level, empty: -O2 as the rest)
#   sanitize  clang, Debug, ASan + UBSan, and the libFuzzer targets
#   tsan      clang, -O1, ThreadSanitizer: every test suite (-O2 took 17 % more
#             compile CPU for 4 % less CPU in its tests)
#   lint      plain's compiler and flags, file by file, configured only (and
#             the generated headers): the compile database scripts/lint.sh reads
# The sanitized flavours keep line tables only (-gline-tables-only: a report's
# stack still names every function, file and line; CANHIL_DEBUG_INFO=full for
# gdb's variables). Every flavour is a unity build (a target's sources compiled
# sixteen at a time, each header parsed once for them: half the time of a build
# from scratch; CANHIL_UNITY=0 compiles file by file, quicker after a one-file
# change).
# Where they are installed (scripts/install-deps.sh installs both):
#   ccache    compiles through it, the cache in the user's cache folder
#             (~/.cache/ccache) with paths taken relative to the checkout, so
#             a second clone of the same commit reuses what the first compiled;
#             CANHIL_CCACHE=0 turns it off
#   mold      links with it (else lld, else the compiler's default linker);
#             CANHIL_LINKER=bfd|lld|mold chooses
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
flavour="${1:-plain}"
shift || true
# CANHIL_OPT overrides the optimisation level of plain and tsan (e.g. -O3).
case "$flavour" in
  plain|lint) opt="${CANHIL_OPT:--O2}"
              args=(-DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=g++ -DCMAKE_C_COMPILER=gcc
                    "-DCMAKE_CXX_FLAGS_RELEASE=$opt -DNDEBUG" "-DCMAKE_C_FLAGS_RELEASE=$opt -DNDEBUG"
                    "-DCANHIL_TEST_OPT=${CANHIL_TEST_OPT--O1}") ;;
  sanitize) args=(-DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang
                  -DCANHIL_SANITIZE=ON -DCANHIL_BUILD_BENCH=OFF) ;;
  tsan) opt="${CANHIL_OPT:--O1}"
        args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_C_COMPILER=clang
              -DCANHIL_SANITIZE=thread -DCANHIL_BUILD_BENCH=OFF) ;;
  *) echo "build.sh: flavour must be plain, sanitize, tsan or lint" >&2; exit 2 ;;
esac
debug=-gline-tables-only
[[ "${CANHIL_DEBUG_INFO:-lines}" == full ]] && debug=-g
case "$flavour" in
  sanitize) args+=("-DCMAKE_CXX_FLAGS_DEBUG=$debug" "-DCMAKE_C_FLAGS_DEBUG=$debug") ;;
  tsan) args+=("-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$opt $debug -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$opt $debug -DNDEBUG") ;;
esac
unity=ON
[[ "${CANHIL_UNITY:-1}" == 0 || "$flavour" == lint ]] && unity=OFF
args+=(-DCMAKE_UNITY_BUILD=$unity -DCMAKE_UNITY_BUILD_BATCH_SIZE=16)

if [[ "${CANHIL_CCACHE:-1}" != 0 ]] && command -v ccache >/dev/null; then
  args+=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Paths relative to the checkout, and the build folder left out of the hash
  # (it is only in the debug information's compile directory), so that another
  # clone of the same commit hits; precompiled headers need the sloppiness.
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  export CCACHE_SLOPPINESS="pch_defines,time_macros,include_file_mtime,include_file_ctime"
else
  args+=(-DCMAKE_C_COMPILER_LAUNCHER= -DCMAKE_CXX_COMPILER_LAUNCHER=)
fi
linker="${CANHIL_LINKER:-}"
if [[ -z "$linker" ]]; then
  if command -v ld.mold >/dev/null; then linker=mold; elif command -v ld.lld >/dev/null; then linker=lld; fi
fi
args+=(-DCANHIL_LINKER="$linker")

cmake -S . -B "build/$flavour" -G Ninja -DCANHIL_WERROR=ON "${args[@]}" >/dev/null
if [[ "$flavour" == lint ]]; then
  ninja -C build/lint rtdb/generated/rtdb_user.h >/dev/null
elif [[ $# -gt 0 ]]; then
  cmake --build "build/$flavour" --target "$@"
else
  cmake --build "build/$flavour"
fi
