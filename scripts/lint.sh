#!/usr/bin/env bash
# lint.sh — clang-format check and clang-tidy (.clang-tidy) over canhil's own
# sources, file by file with the plain build's compiler and flags (the compile
# database of build/lint: scripts/build.sh lint configures it, since the
# builds themselves compile sources in batches). Fails on any finding.
#   scripts/lint.sh [--db BUILD_DIR] [--files REGEX] [--no-format]
# --db: the build whose compile_commands.json to use (default build/lint,
# configured first); --files: which of its files clang-tidy reads
# (default canhil's sources); --no-format: clang-tidy only.
# clang-tidy's result per file is cached (scripts/lint_tidy.py: a file whose
# preprocessed text, arguments, configuration and clang-tidy are unchanged is
# not analysed again); CANHIL_TIDY_CACHE=0 turns the cache off.
# Most checks run over batches of up to 32 files compiled as one unit (the
# headers walked once for them); the static analyser and the checks that
# depend on the main file run file by file (scripts/lint_tidy.py says which);
# CANHIL_TIDY_BATCH=1 runs every check file by file, the reference the
# batches give the same findings as (tests/scripts/lint_test.sh).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
db=build/lint
files='frames/src|wire/src|external/src|userbus/src|can_nodes/src|kinematics/src|physics/src|emulator/src|rtdb/src|pman/src|laptop/src|vision_emu/src|timing/src|lockstep/src|control/src|viewer/src|app/'
format=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --db) db=$2; shift 2 ;;
    --files) files=$2; shift 2 ;;
    --no-format) format=0; shift ;;
    *) echo "lint.sh: unknown argument $1 (takes --db DIR, --files REGEX, --no-format)" >&2; exit 2 ;;
  esac
done
if [[ "$db" == build/lint ]]; then
  bash scripts/build.sh lint
elif [[ ! -f "$db/compile_commands.json" ]]; then
  echo "lint.sh: $db/compile_commands.json is missing" >&2
  exit 2
fi
if [[ $format -eq 1 ]]; then
  git ls-files '*.cpp' '*.hpp' | xargs clang-format --dry-run --Werror
fi
options=()
[[ "${CANHIL_TIDY_CACHE:-1}" == 0 ]] && options=(--cache '')
options+=(--batch "${CANHIL_TIDY_BATCH:-32}")
# clang-tidy exits non-zero on any finding (WarningsAsErrors). The compile
# database is g++'s: -Wno-unknown-warning-option for its g++-only warnings.
python3 scripts/lint_tidy.py -p "$db" "${options[@]}" "$files" > "$db/clang-tidy.log" 2>&1 || {
  grep -E "error:|warning:" "$db/clang-tidy.log" | sort -u >&2
  tail -1 "$db/clang-tidy.log" >&2
  echo "lint: clang-tidy found problems (full log: $db/clang-tidy.log)" >&2
  exit 1
}
echo "lint: clang-format and clang-tidy clean ($(tail -1 "$db/clang-tidy.log" | sed 's/^lint_tidy: //'))"
