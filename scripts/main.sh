#!/usr/bin/env bash
# main.sh — the main job of the README: set everything up, build canhil, then
# show it working, one short section each: the message set, a recorded bus
# decoded, physics calibration, a vision frame, and the demo (one robot's whole
# loop) in virtual time with its timing report, the regression tests of the
# shipped examples (canhil test), and in real time on vcan. Every
# file it writes is under build/plain/main/.
#   bash scripts/main.sh                  everything (installs packages and builds first)
#   bash scripts/main.sh --no-realtime    without the real-time demo on vcan
# CANHIL_BUILD=DIR uses an existing build (no install, no build): what the test does.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
realtime=1
for a in "$@"; do
  case "$a" in
    --no-realtime) realtime=0 ;;
    *) echo "main.sh: unknown argument $a (takes --no-realtime)" >&2; exit 2 ;;
  esac
done
if [[ -z "${CANHIL_BUILD:-}" ]]; then
  bash scripts/install-deps.sh main
  echo "== building canhil, canhil-hwcomm and canhil-agent (build/plain; the full log in build/plain/main-build.log)"
  mkdir -p build/plain
  # Only the programs this job runs; scripts/test.sh builds the rest.
  bash scripts/build.sh plain canhil canhil-hwcomm canhil-agent >build/plain/main-build.log 2>&1 ||
    { tail -20 build/plain/main-build.log; exit 1; }
fi
bin=${CANHIL_BUILD:-build/plain}
canhil=$bin/app/canhil
out=$bin/main
mkdir -p "$out"
section() { printf '\n== %s\n' "$*"; }

section "1. the message set: what each frame on a robot's bus carries (frames/canhil.dbc; canhil frames list)"
"$canhil" frames list

section "2. a recorded robot bus, decoded: the first frames and the summary (frames/samples/one_robot.log; canhil dump)"
"$canhil" dump --log frames/samples/one_robot.log --head 4 2>&1

section "3. physics against the reference figures: a ball dropped from 1 m, a robot driving (docs/physics.md)"
"$canhil" experiment ball-drop
"$canhil" experiment drive

section "4. emulated vision: one frame of one robot among five, drawn in $out/vision.svg (docs/vision.md)"
"$canhil" experiment vision --svg "$out/vision.svg"

section "5. the demo in virtual time: one robot's whole loop, which drives to the ball and scores, its bus on a timed wire at the DBC's 1 Mbit/s ($out/demo.log, demo.csv)"
"$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --quiet --trace "$out/demo.log" \
  --world-log "$out/demo.csv" | tee "$out/demo.txt"

section "6. the demo's bus: periods, jitter and FTT compliance of every frame, stamped at its end of frame (canhil timing --stamps end $out/demo.log)"
"$canhil" timing --stamps end "$out/demo.log"

section "7. what the message set allows in the worst case, and the demo's bus inside those bounds (canhil timing --analyse; $out/analysis.txt, docs/timing.md)"
"$canhil" timing --analyse --stamps end "$out/demo.log" > "$out/analysis.txt"
grep -E '^(  worst EC|Schedulable|NOT schedulable|Every observation|[0-9]+ observations OUTSIDE)' \
  "$out/analysis.txt"

section "8. the demo on the timed wire with a fault: the handler's controller goes bus-off at 1 s and restarts 800 ms later, the robot brakes and drives on ($out/wire.log; docs/wire.md)"
"$canhil" run --virtual-time --config emulator/scenarios/one_robot_on_the_wire.toml --quiet --trace "$out/wire.log" \
  --world-log "$out/wire.csv" | tee "$out/wire.txt" | grep -E "GOAL|on the wire at|  handler "
# The report says what the bus-off cost (M6 missing for 840 ms): exit status 1, expected here.
{ "$canhil" timing --stamps end "$out/wire.log" || true; } | grep -E "M6_1 +missing"

section "9. the team's regression tests: canhil test on the shipped examples, a verdict per expectation and a JUnit report for the CI ($out/tests.xml; docs/testing-your-software.md)"
"$canhil" test emulator/scenarios/tests/*.toml --junit "$out/tests.xml" --artifacts "$out/tests" > "$out/tests.txt" ||
  { cat "$out/tests.txt"; exit 1; }
grep -E "^canhil test:" "$out/tests.txt"

if [[ $realtime -eq 1 ]]; then
  section "10. the same demo in real time on vcan0: emulator, handler and agent as three processes (scripts/demo.sh)"
  bash vcan_setup/with-vcan.sh -- bash scripts/demo.sh 20 "$bin"
fi

section "what happened"
goal=$(grep -m1 "GOAL" "$out/demo.txt" | sed 's/^ *//' || true)
echo "   virtual time: ${goal:-no goal}; $(grep -m1 'real time)' "$out/demo.txt" | sed 's/^canhil run: //')"
wire_goal=$(grep -m1 "GOAL" "$out/wire.txt" | sed 's/^ *//' || true)
echo "   on a timed wire, with the handler's controller bus-off from 1 s to 1.8 s: ${wire_goal:-no goal}"
echo "   regression tests: $(grep -m1 '^canhil test:' "$out/tests.txt" | sed 's/^canhil test: //')"
echo "   files: $out/ (demo.log: candump trace, demo.csv: world log, vision.svg); docs/user-guide.md goes on from here"

section "watch it: the demo again at twice real time in the viewer, with plots (docs/viewer.md; saves in $out/saves)"
echo "   open the address below in a browser; drag the robot or the ball, pause, step"
"$canhil" run --virtual-time --config emulator/scenarios/one_robot.toml --quiet --speed 2 --duration 10 \
  --view-hold "${VIEW_HOLD:-10}" --save-dir "$out/saves" --no-control | grep -E "viewer|done after"
