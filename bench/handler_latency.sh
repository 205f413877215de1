#!/usr/bin/env bash
# handler_latency.sh [SECONDS] — the reference handler's latency from a frame's
# kernel receive timestamp to its RTDB write (issue 5 target: p99 <= 200 us on
# a quiet machine), measured twice on vcan0 for SECONDS each (default 20), the
# handler with SCHED_FIFO:
#   quiet: only the handler, fed 200 M8 frames/s by can-utils' cangen
#   busy:  the handler next to the full emulator (canhil nodes, with physics)
# Where the kernel has no CAN this runs natively on canhil's user-space bus
# (with-vcan.sh says which bus on its first line); there the receive timestamp
# is the bus's delivery time, the broker's hop before it not counted.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds="${1:-20}"
build="${BUILD:-build/plain}"
[[ -x "$build/laptop/canhil-hwcomm" ]] || bash scripts/build.sh plain >/dev/null
exec vcan_setup/with-vcan.sh -- bash -c "
  export AGENT=1 RTDB_KEY=0x5D000000
  echo '== quiet: canhil-hwcomm alone, 200 M8 frames/s from cangen'
  cangen vcan0 -I 141 -L 8 -D r -g 5 &
  gen=\$!
  $build/laptop/canhil-hwcomm --iface vcan0 --duration $seconds --rt-priority 50 | grep latency
  kill \$gen
  echo '== busy: canhil-hwcomm next to the emulator (canhil nodes)'
  $build/app/canhil nodes --iface vcan0 --quiet --duration $((seconds + 2)) > /tmp/canhil-latency-nodes.log 2>&1 &
  sleep 1
  $build/laptop/canhil-hwcomm --iface vcan0 --duration $seconds --rt-priority 50 | grep latency
  wait
  grep -E 'physics' /tmp/canhil-latency-nodes.log"
