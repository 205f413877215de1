#!/usr/bin/env bash
# same_trace.sh BUILD SOURCE — lockstep with the team's processes gives the
# same trace and world log, byte for byte, on the kernel's vcan (here or in
# the VM runner) and on canhil's user-space bus natively: the same scenario,
# seed and binaries (canhil run --external with canhil-hwcomm and
# canhil-agent as processes, 3 s of virtual time), on the instant bus
# (--bit-rate 0: the kernel's vcan cannot carry canhil's wire; the timed one's
# determinism is timed_same_trace.sh's).
set -euo pipefail
build="$1"
source="$2"
out="$(mktemp -d /tmp/canhil-same-trace.XXXXXX)"
trap 'rm -rf "$out"' EXIT
run() {
  local mode="$1"
  PATH="$build/laptop:$build/app:$PATH" CANHIL_BIN="$build/app/canhil" \
    "$source/vcan_setup/with-vcan.sh" --mode "$mode" --own-ipc -- \
    "$build/app/canhil" run --no-control --quiet --config "$source/emulator/scenarios/one_robot.toml" --seed 3 \
    --external --duration 3 --bit-rate 0 --process "canhil-hwcomm --iface {iface}" --process "canhil-agent --pose -3,0,-90" \
    --trace "$out/$mode.log" --world-log "$out/$mode.csv" > "$out/$mode.out" 2>&1 ||
    { echo "same_trace: the run on $mode failed:"; cat "$out/$mode.out"; exit 1; }
}
run kernel
run user
frames=$(wc -l < "$out/kernel.log")
[[ $frames -gt 500 ]] || { echo "same_trace: only $frames frames on the kernel's vcan"; exit 1; }
cmp "$out/kernel.log" "$out/user.log" || { echo "same_trace: the traces differ"; diff "$out/kernel.log" "$out/user.log" | head -20; exit 1; }
cmp "$out/kernel.csv" "$out/user.csv" || { echo "same_trace: the world logs differ"; exit 1; }
echo "same_trace: $frames frames and the world log identical on the kernel's vcan and on the user-space bus"
