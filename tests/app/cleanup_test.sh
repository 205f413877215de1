#!/usr/bin/env bash
# cleanup_test.sh BUILD_DIR — what a canhil process leaves on the machine.
# A command whose output's reader goes away (`canhil run | head`) stops as
# Ctrl-C stops it, removing what it set up, and then ends by SIGPIPE as the
# shell expects (status 141):
# - `canhil run --virtual-time`: its RTDB's shared memory segments and its
#   control socket are gone;
# - `canhil match --jobs 2`: the batch stops early (its last progress line
#   counts fewer matches than asked for) and no worker's segments are left.
# A run killed outright (SIGKILL) cannot clean up: the next run removes the
# segments it left (its own kind of key, nobody attached, its creator gone).
# A run never takes a key range a live process holds; it claims its range
# from the start, and a run and a batch's workers give their claims back.
# Every run stops within a second of virtual time: cheap under the sanitizers.
set -euo pipefail
build=$1
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
canhil="$build/app/canhil"
dir=$(mktemp -d)
# Whatever this test started in the background goes with it, even when it fails half-way.
cleanup() {
  local job
  for job in $(jobs -p); do kill -KILL "$job" 2> /dev/null || true; done
  [[ ! -f "$dir/holder" ]] || kill "$(cut -d' ' -f2 "$dir/holder")" 2> /dev/null || true
  rm -rf "$dir"
}
trap cleanup EXIT
# Keys of this test only (a process's sets: base, base + 64; a match worker's:
# base + its number << 16).
base=$((0x56000000 + (($$ & 0xFF) << 8)))
failed=0
fail() { echo "FAIL: $*"; failed=1; }
# Segments whose key is in [LO, HI).
segments_in() {
  local key rest
  ipcs -m | while read -r key rest; do
    [[ $key == 0x* ]] && ((key >= $1 && key < $2)) && echo "$key"
  done || true
}
# The run's and the workers' segments, keys in [base, base + 0x40000).
left_segments() { segments_in "$base" $((base + 0x40000)); }

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

# Killed outright, a run in virtual time paced at real time leaves its
# segments (keys 0x58000000 + its pid << 8); the next run removes them. An
# empty RTDB_KEY is no key (the RTDB reads it so): the run takes its own.
# Every run sweeps such orphans, so a run of a test beside this one (ctest -j)
# may be the one that removes them: what counts is that none is left after
# the next run.
RTDB_KEY= "$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --duration 600 --speed 1 --no-view \
  --no-control --quiet > "$dir/killed.out" 2>&1 &
killed=$!
killed_base=$((0x58000000 + ((killed & 0xFFFF) << 8)))
killed_segments() { segments_in "$killed_base" $((killed_base + 0x100)); }
for _ in $(seq 300); do
  [[ -n "$(killed_segments)" ]] && break
  sleep 0.1
done
orphans=$(killed_segments | wc -l)
# Its range is claimed on its last key from the start (two runs starting
# together never choose one range).
[[ -n "$(segments_in $((killed_base + 0xFF)) $((killed_base + 0x100)))" ]] ||
  fail "a run does not claim its key range: no segment at $(printf '0x%08x' $((killed_base + 0xFF)))"
kill -KILL "$killed"
wait "$killed" 2> /dev/null || true
if [[ $orphans == 0 ]]; then
  fail "the run to be killed had no segments after 30 s: $(cat "$dir/killed.out")"
else
  "$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --duration 0.1 --no-view --no-control \
    --quiet > "$dir/next.out" 2>&1 || fail "the next run failed: $(cat "$dir/next.out")"
  [[ -z "$(killed_segments)" ]] ||
    fail "the next run left $(killed_segments | wc -l) of the $orphans segments of the killed one: $(killed_segments | tr '\n' ' ')"
fi

# A run whose key range a live process holds (their ids share the low 16
# bits, or another run stepped into it) takes the next free range and never
# touches that process's segment (the RTDB would take a segment of another
# size that nobody is attached to for a stale one of its own and remove it).
set +e
(
  key=$((0x58000000 + ((BASHPID & 0xFFFF) << 8)))
  perl -e 'shmget($ARGV[0], 64, 01000 | 0600) // die "shmget: $!\n"; sleep 120' "$key" > /dev/null 2>&1 &
  echo "$key $!" > "$dir/holder"
  for _ in $(seq 100); do
    [[ -n "$(segments_in "$key" $((key + 1)))" ]] && break
    sleep 0.1
  done
  exec "$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --duration 0.1 --no-view --no-control \
    --quiet > "$dir/held.out" 2>&1
)
status=$?
set -e
read -r held holder < "$dir/holder"
[[ $status == 0 ]] || fail "a run beside a held key range ended with status $status: $(cat "$dir/held.out")"
[[ -n "$(segments_in "$held" $((held + 1)))" ]] ||
  fail "a run removed the segment a live process holds at $(printf '0x%08x' "$held") (its own key range)"
[[ -z "$(segments_in $((held + 0x100)) $((held + 0x200)))" ]] ||
  fail "the run beside a held range left its claim: $(segments_in $((held + 0x100)) $((held + 0x200)) | tr '\n' ' ')"
kill "$holder" 2> /dev/null || true
rm -f "$dir/holder"
ipcrm -M "$held" 2> /dev/null || true

# A batch's workers claim ranges of their own and give them back when the
# batch stops (Ctrl-C): no segment any of its processes created is left.
"$canhil" match emulator/scenarios/two_teams.toml --seeds 1..400 --jobs 2 --halves 1 --half-minutes 0.05 \
  --no-records > /dev/null 2> "$dir/batch.err" &
batch=$!
creators() { awk 'NR > 1 { print $5 }' /proc/sysvipc/shm; }
workers=()
for _ in $(seq 300); do
  mapfile -t workers < <(pgrep -P "$batch" || true)
  if [[ ${#workers[@]} == 2 ]] && creators | grep -qx -e "${workers[0]}" && creators | grep -qx -e "${workers[1]}"; then
    break
  fi
  sleep 0.1
done
[[ ${#workers[@]} == 2 ]] || fail "the batch had ${#workers[@]} workers, not 2: $(cat "$dir/batch.err")"
kill -INT "$batch"
status=0
wait "$batch" || status=$?
[[ $status == 130 ]] || fail "the batch stopped by Ctrl-C ended with status $status, not 130: $(tail -3 "$dir/batch.err")"
for pid in "$batch" "${workers[@]}"; do
  left=$(creators | grep -cx -e "$pid" || true)
  [[ $left == 0 ]] || fail "the batch's process $pid left $left segments"
done

# Ctrl-C while a run holds its viewer up after the end (--view-hold) ends it
# there and then, with the run's own status (it ran to its end), its segments
# removed.
RTDB_KEY=$((base + 0x10000)) "$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --duration 0.1 \
  --view-port 0 --view-hold 600 --no-control > "$dir/hold.out" 2> "$dir/hold.err" &
hold=$!
for _ in $(seq 300); do
  grep -q 'stays up' "$dir/hold.out" && break
  sleep 0.1
done
grep -q 'stays up' "$dir/hold.out" || fail "the run did not hold its viewer up: $(cat "$dir/hold.out" "$dir/hold.err")"
kill -INT "$hold"
for _ in $(seq 100); do
  kill -0 "$hold" 2> /dev/null || break
  sleep 0.1
done
if kill -0 "$hold" 2> /dev/null; then
  fail "Ctrl-C did not end a run holding its viewer up within 10 s"
  kill -KILL "$hold"
fi
status=0
wait "$hold" || status=$?
[[ $status == 0 ]] || fail "a run stopped while holding its viewer ended with status $status, not 0: $(cat "$dir/hold.err")"
[[ -z "$(left_segments)" ]] || fail "a run stopped while holding its viewer left segments: $(left_segments | tr '\n' ' ')"

# A sanitizer's report never hides behind the signal the process ended by.
if grep -s -l -E "Sanitizer|runtime error:" "$dir/run.err" "$dir/match.err" "$dir/next.out" "$dir/held.out" \
  "$dir/batch.err" "$dir/hold.err"; then
  fail "a sanitizer reported: $(grep -h -A5 -E "Sanitizer|runtime error:" "$dir"/*.err "$dir/next.out" | head -20)"
fi

[[ $failed == 0 ]] || exit 1
echo "cleanup: run and match stopped on SIGPIPE (141) with nothing left behind (match: $done_line);" \
  "the $orphans segments of a killed run removed by the next; a held key range left alone;" \
  "claims given back by a run and by a stopped batch's workers"
