#!/usr/bin/env bash
# lint.sh — clang-format check and clang-tidy (.clang-tidy) over canhil's own
# sources, using build/plain's compile database. Fails on any finding.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
[[ -f build/plain/compile_commands.json ]] || bash scripts/build.sh plain >/dev/null
git ls-files '*.cpp' '*.hpp' | xargs clang-format --dry-run --Werror
# run-clang-tidy prints findings and exits non-zero on any (WarningsAsErrors).
# -Wno-unknown-warning-option: the compile database is g++'s (its -Wno-restrict
# is a g++ 12 workaround clang does not know).
run-clang-tidy -p build/plain -quiet -extra-arg=-Wno-unknown-warning-option 'frames/src|can_nodes/src|kinematics/src|physics/src|emulator/src|rtdb/src|pman/src|laptop/src|vision_emu/src|timing/src|control/src|viewer/src|app/' > build/plain/clang-tidy.log 2>&1 || {
  grep -E "error:|warning:" build/plain/clang-tidy.log | sort -u >&2
  echo "lint: clang-tidy found problems (full log: build/plain/clang-tidy.log)" >&2
  exit 1
}
echo "lint: clang-format and clang-tidy clean"
