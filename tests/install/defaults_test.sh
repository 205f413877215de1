#!/usr/bin/env bash
# defaults_test.sh SOURCE_DIR WORK_DIR — canhil configured as a packager or a
# team embedding it would (no options): warnings must not be errors there;
# only the project's own scripts and CI ask for -Werror.
set -euo pipefail
src=$1
work=$2
rm -rf "$work"
cmake -S "$src" -B "$work" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCANHIL_BUILD_TESTS=OFF -DCANHIL_BUILD_BENCH=OFF \
  >/dev/null
grep -q '^CANHIL_WERROR:BOOL=OFF$' "$work/CMakeCache.txt" || { echo "FAIL: CANHIL_WERROR is not OFF by default"; exit 1; }
if grep -q -- '-Werror' "$work/build.ninja"; then
  echo "FAIL: a default configuration compiles with -Werror"
  exit 1
fi
echo "defaults: warnings are not errors unless CANHIL_WERROR=ON"
