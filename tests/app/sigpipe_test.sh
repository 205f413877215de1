#!/usr/bin/env bash
# sigpipe_test.sh BUILD_DIR — a command whose output's reader goes away
# (`canhil run | head`) stops as Ctrl-C stops it, removing what it set up on
# the machine, and then ends by SIGPIPE as the shell expects (status 141):
# - `canhil run --virtual-time`: its RTDB's shared memory segments and its
#   control socket are gone;
# - `canhil match --jobs 2`: the batch stops early (its last progress line
#   counts fewer matches than asked for) and no worker's segments are left.
# Both stop within a second of virtual time: cheap under the sanitizers too.
set -euo pipefail
build=$1
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
canhil="$build/app/canhil"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# Keys of this test only (a process's sets: base, base + 64; a match worker's:
# base + its number << 16).
base=$((0x56000000 + (($$ & 0xFF) << 8)))
failed=0
fail() { echo "FAIL: $*"; failed=1; }
# Segments whose key is in [base, base + 0x40000): the run's and the workers'.
left_segments() {
  local key rest
  ipcs -m | while read -r key rest; do
    [[ $key == 0x* ]] && ((key >= base && key < base + 0x40000)) && echo "$key"
  done || true
}

# pipefail off while canhil writes into head: its own status is the point.
set +o pipefail
RTDB_KEY=$base "$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --duration 600 --no-view \
  --control "$dir/control" 2> "$dir/run.err" | head -n 2 > "$dir/run.out"
status=${PIPESTATUS[0]}
set -o pipefail
[[ $status == 141 ]] || fail "canhil run ended with status $status, not by SIGPIPE (141): $(cat "$dir/run.err")"
[[ $(wc -l < "$dir/run.out") == 2 ]] || fail "canhil run printed $(wc -l < "$dir/run.out") lines before its reader left"
[[ ! -e "$dir/control" ]] || fail "canhil run left its control socket $dir/control"
[[ -z "$(left_segments)" ]] || fail "canhil run left shared memory segments: $(left_segments | tr '\n' ' ')"

set +o pipefail
RTDB_KEY=$base "$canhil" match emulator/scenarios/two_teams.toml --seeds 1..400 --jobs 2 --halves 1 \
  --half-minutes 0.05 --no-records 2> "$dir/match.err" | head -n 1 > /dev/null
status=${PIPESTATUS[0]}
set -o pipefail
[[ $status == 141 ]] || fail "canhil match ended with status $status, not by SIGPIPE (141): $(tail -3 "$dir/match.err")"
done_line=$(grep -o '[0-9]*/400 done' "$dir/match.err" | tail -1 || true)
[[ -n "$done_line" && "${done_line%%/*}" -lt 400 ]] ||
  fail "canhil match went on after its reader left (last progress: '${done_line:-none}')"
[[ -z "$(left_segments)" ]] || fail "canhil match left shared memory segments: $(left_segments | tr '\n' ' ')"

# A sanitizer's report never hides behind the signal the process ended by.
if grep -l -E "Sanitizer|runtime error:" "$dir/run.err" "$dir/match.err"; then
  fail "a sanitizer reported: $(grep -h -A5 -E "Sanitizer|runtime error:" "$dir/run.err" "$dir/match.err" | head -20)"
fi

[[ $failed == 0 ]] || exit 1
echo "sigpipe: run and match stopped on SIGPIPE, status 141, nothing left behind (match: $done_line)"
