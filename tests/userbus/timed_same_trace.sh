#!/usr/bin/env bash
# timed_same_trace.sh BUILD SOURCE — lockstep with the team's processes on a
# timed wire (--bit-rate 1000000: the user-space bus's broker runs the wire on
# the run's virtual clock) gives the same trace and world log twice, byte for
# byte, and the trace is the wire's: frames stamped at their end of frame,
# FTT-clean by `canhil timing --stamps end`. 3 s of virtual time each, the
# reference handler and agent as processes.
set -euo pipefail
build="$1"
source="$2"
out="$(mktemp -d /tmp/canhil-timed-trace.XXXXXX)"
trap 'rm -rf "$out"' EXIT
run() {
  PATH="$build/laptop:$build/app:$PATH" CANHIL_BIN="$build/app/canhil" \
    "$source/vcan_setup/with-vcan.sh" --mode user --own-ipc -- \
    "$build/app/canhil" run --no-control --quiet --config "$source/emulator/scenarios/one_robot.toml" --seed 3 \
    --external --duration 3 --bit-rate 1000000 --process "canhil-hwcomm --iface {iface}" \
    --process "canhil-agent --pose -3,0,-90" --trace "$out/$1.log" --world-log "$out/$1.csv" > "$out/$1.out" 2>&1 ||
    { echo "timed_same_trace: run $1 failed:"; cat "$out/$1.out"; exit 1; }
}
run first
run second
grep -q "each robot's bus on a timed wire at 1000 kbit/s (--bit-rate; --bit-rate 0: instant), the user-space bus's broker on this run's clock" "$out/first.out" ||
  { echo "timed_same_trace: the run did not put its bus on the wire:"; head -8 "$out/first.out"; exit 1; }
frames=$(wc -l < "$out/first.log")
[[ $frames -gt 500 ]] || { echo "timed_same_trace: only $frames frames"; exit 1; }
cmp "$out/first.log" "$out/second.log" ||
  { echo "timed_same_trace: the traces differ"; diff "$out/first.log" "$out/second.log" | head -20; exit 1; }
cmp "$out/first.csv" "$out/second.csv" || { echo "timed_same_trace: the world logs differ"; exit 1; }
# The wire's stamps: the first TM ends 119 us into the run (its bits at 1 Mbit/s), not at 0.
head -1 "$out/first.log" | grep -q "^(0000000000.000119) vcan0 010#" ||
  { echo "timed_same_trace: the first frame is not the TM at its end of frame:"; head -2 "$out/first.log"; exit 1; }
"$build/app/canhil" timing --stamps end --bit-rate 1000000 "$out/first.log" > "$out/timing.txt" 2>&1 || true
grep -q "FTT compliance: no violations" "$out/timing.txt" ||
  { echo "timed_same_trace: FTT violations on the wire:"; tail -20 "$out/timing.txt"; exit 1; }
echo "timed_same_trace: $frames frames and the world log identical twice on the timed wire, FTT-clean"
