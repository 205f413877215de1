#!/usr/bin/env bash
# vcan-up.sh — bring up virtual CAN interfaces, idempotently.
#
#   vcan-up.sh N          creates and brings up vcan0 .. vcan(N-1)
#   vcan-up.sh NAME...    creates and brings up the named interfaces
#
# Needs root (or CAP_NET_ADMIN) and a kernel with the vcan module. Running it
# again changes nothing. Exit status: 0 all up, 2 set-up impossible (says why).
set -euo pipefail

if [[ $# -eq 0 ]]; then
  echo "usage: $0 N | NAME..." >&2
  exit 2
fi
names=()
if [[ $# -eq 1 && "$1" =~ ^[0-9]+$ ]]; then
  for ((i = 0; i < $1; i++)); do names+=("vcan$i"); done
else
  names=("$@")
fi

if ! command -v ip >/dev/null 2>&1; then
  echo "vcan-up: the 'ip' command is missing; install iproute2 (apt-get install iproute2)" >&2
  exit 2
fi
if [[ ! -d /sys/module/vcan ]]; then
  if ! modprobe vcan 2>/dev/null && [[ ! -d /sys/module/vcan ]]; then
    echo "vcan-up: this kernel has no vcan module (modprobe vcan failed)." >&2
    echo "vcan-up: run the command inside the VM runner instead: vcan_setup/vm-run.sh --ifaces ${#names[@]} -- COMMAND" >&2
    exit 2
  fi
fi
modprobe can-raw 2>/dev/null || true

for name in "${names[@]}"; do
  if ! ip link show "$name" >/dev/null 2>&1; then
    ip link add dev "$name" type vcan
  fi
  ip link set "$name" up
  echo "vcan-up: $name is up"
done
