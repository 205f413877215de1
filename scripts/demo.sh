#!/usr/bin/env bash
# demo.sh — the README demo in real time on vcan0: the emulator (`canhil run`
# with the one-robot scenario), the reference handler and the reference agent,
# each its own process as on a robot, for SECONDS (default 20; BUILD_DIR default
# build/plain); `canhil timing`
# listens to the bus meanwhile and prints its report at the end.
#
# Needs vcan0: run it through vcan_setup/with-vcan.sh (scripts/main.sh does),
# which uses this machine's vcan or, where the kernel has no CAN, canhil's
# user-space bus natively (the VM runner only when neither works).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds="${1:-20}"
bin="${2:-build/plain}"
export AGENT=1
export RTDB_KEY="${RTDB_KEY:-$((0x5E000000 + (($$ & 0xFFF) << 8)))}"
log=$(mktemp -d /tmp/canhil-demo.XXXXXX)
pids=()
cleanup() {
  # SIGTERM to each (they take it as Ctrl-C and print their summaries; a SIGINT
  # could be lost: a script's background job starts with SIGINT ignored).
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

"$bin/app/canhil" run --config emulator/scenarios/one_robot.toml --duration "$seconds" --quiet > "$log/run.txt" 2>&1 &
run_pid=$!
sleep 1  # the emulator creates the RTDB and starts the bus
"$bin/app/canhil" timing vcan0 --seconds "$((seconds - 3))" > "$log/timing.txt" 2>&1 &
timing_pid=$!
"$bin/laptop/canhil-hwcomm" --iface vcan0 > "$log/hwcomm.txt" 2>&1 &
pids+=($!)
"$bin/laptop/canhil-agent" --pose -3,0,-90 > "$log/agent.txt" 2>&1 &
pids+=($!)
echo "demo: emulator, handler and agent running for ${seconds} s on vcan0 ..."
wait "$run_pid" || true
timing_status=0
wait "$timing_pid" || timing_status=$?
cleanup
pids=()
echo "== the emulator (canhil run, real time)"
cat "$log/run.txt"
echo "== the reference agent (canhil-agent)"
grep -E "kick|frames" "$log/agent.txt" || true
echo "== the handler's summary (canhil-hwcomm)"
tail -n 5 "$log/hwcomm.txt"
echo "== timing of the live bus (canhil timing vcan0; exit status $timing_status)"
sed -n '1,/^FTT compliance/p' "$log/timing.txt"
if [[ -n "${CANHIL_IN_VM:-}" ]]; then
  where="inside the VM runner, whose timer and wake-up emulation makes frames late or missing"
else
  where="on $("$bin/app/canhil" bus list >/dev/null 2>&1 && [[ -n "${LD_PRELOAD:-}" ]] && echo "canhil's user-space bus" || echo "this machine's vcan"), natively; a loaded 2-core machine still makes some frames late"
fi
echo "(the violations one by one: $log/timing.txt. Measured $where;"
echo " the virtual-time run above is the exact reference)"
