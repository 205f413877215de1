#!/usr/bin/env bash
# with-vcan.sh — run a command where vcan0..vcan(N-1) exist, wherever that is.
#
#   with-vcan.sh [--ifaces N] -- COMMAND [ARG...]
#
# On a kernel with vcan: brings the interfaces up here (vcan-up.sh) and runs
# COMMAND directly. On a kernel without CAN: runs COMMAND inside the VM
# runner (vm-run.sh). CANHIL_VCAN_MODE=host or =vm forces one. When neither
# works it fails (exit 125) and says why: SocketCAN tests never pass by skipping.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ifaces=1
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ifaces) ifaces="$2"; shift 2 ;;
    --) shift; break ;;
    *) echo "with-vcan: unknown option $1 (put the command after --)" >&2; exit 125 ;;
  esac
done

if [[ -n "${CANHIL_IN_VM:-}" ]]; then exec "$@"; fi  # already inside the VM

mode="${CANHIL_VCAN_MODE:-auto}"
if [[ "$mode" != vm ]]; then
  if "$here/vcan-up.sh" "$ifaces" >/tmp/canhil-vcan-up.log 2>&1; then
    echo "with-vcan: running on this machine's vcan" >&2
    exec "$@"
  fi
  if [[ "$mode" == host ]]; then
    echo "with-vcan: CANHIL_VCAN_MODE=host but vcan cannot be set up here:" >&2
    cat /tmp/canhil-vcan-up.log >&2
    exit 125
  fi
fi
echo "with-vcan: this kernel has no usable vcan; running inside the VM runner" >&2
exec "$here/vm-run.sh" --ifaces "$ifaces" -- "$@"
