#!/usr/bin/env bash
# main_job_test.sh BUILD_DIR — the README's main job (without its real-time
# part) tells its story without drowning it: a few lines of the sample trace
# and its summary, the demo's outcome and its timing report, every section
# headed by one line that says what it shows and where its files are.
set -euo pipefail
build=$1
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
out=$(VIEW_HOLD=1 CANHIL_BUILD="$build" bash scripts/main.sh --no-realtime 2>&1)
fail() { echo "FAIL: $*"; echo "$out"; exit 1; }
# grep -q reads a here-string, never a pipe: it leaves at the first match, and
# under pipefail the writer's SIGPIPE would fail the check that matched.
lines=$(echo "$out" | wc -l)
[[ $lines -le 124 ]] || fail "the main job prints $lines lines; a newcomer should not have to scroll through a trace"
trace_lines=$(echo "$out" | grep -c '^(1700000000' || true)
[[ $trace_lines -le 8 ]] || fail "$trace_lines lines of the sample trace (a few are enough)"
grep -q 'canhil dump: 183 frames from frames/samples/one_robot.log' <<< "$out" || fail "no decode summary"
grep -q 'GOAL at' <<< "$out" || fail "the demo's outcome is missing"
grep -q 'FTT compliance: no violations' <<< "$out" || fail "the demo's timing report is missing"
grep -q '^Schedulable: every message meets its deadline' <<< "$out" || fail "the message set's analysis is missing"
grep -q '^Every observation is inside its bound' <<< "$out" || fail "the demo's trace against the bounds is missing"
grep -q '^   virtual time: GOAL at' <<< "$out" || fail "no closing line with the outcome"
# The timed wire (docs/wire.md): the handler's controller bus-off and back, the robot braked and scoring late.
grep -q 'on the wire at 1000 kbit/s' <<< "$out" || fail "the timed wire's report is missing"
grep -qE 'handler +error-active, .* 1 bus-off, 1 restarts' <<< "$out" || fail "the handler's bus-off and restart are missing"
grep -q '^   on a timed wire, with the handler.s controller bus-off from 1 s to 1.8 s: GOAL at' <<< "$out" ||
  fail "no closing line for the timed wire"
grep -q 'M6_1   missing' <<< "$out" || fail "the timing report does not show the M6 the bus-off cost"
# The regression tests (docs/testing-your-software.md): every shipped example passed, with a JUnit report.
grep -qE '^canhil test: [0-9]+ file\(s\), [0-9]+ expectation\(s\): [0-9]+ passed, 0 failed, 0 file\(s\) with errors' <<< "$out" ||
  fail "the regression tests' summary is missing"
grep -q '^   regression tests: ' <<< "$out" || fail "no closing line for the regression tests"
[[ -s "$build/main/tests.xml" ]] || fail "no JUnit report $build/main/tests.xml"
grep -qE 'viewer (at|stays up)|no viewer' <<< "$(tail -3 <<< "$out")" || fail "the main job does not end with the viewer's address"
while IFS= read -r header; do
  [[ "$header" == *"("*")"* ]] || fail "section header without where its files are: $header"
done < <(echo "$out" | grep '^== [0-9]')
sections=$(echo "$out" | grep -c '^== [0-9]')
[[ $sections -ge 6 ]] || fail "only $sections sections"
echo "main job: $lines lines, $sections sections, $trace_lines trace lines, outcome and timing shown"
