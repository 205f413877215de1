#!/usr/bin/env bash
# with-vcan.sh — run a command where vcan0..vcan(N-1) exist, wherever that is.
#
#   with-vcan.sh [--ifaces N] [--mode host|user|vm|kernel] [--own-ipc] -- COMMAND [ARG...]
#
# Three places, tried in this order unless a mode is forced (--mode, or
# CANHIL_VCAN_MODE):
#   host    this machine's kernel has vcan: the interfaces are brought up here
#           (vcan-up.sh) and COMMAND runs directly;
#   user    the kernel has no CAN (WSL2, Docker Desktop, CI containers):
#           COMMAND runs natively on canhil's user-space bus (canhil bus exec,
#           docs/vcan.md), which needs the canhil program ($CANHIL_BIN, else
#           canhil on the PATH, else the build tree's or the installed one);
#   vm      COMMAND runs inside the VM runner (vm-run.sh): a kernel with vcan
#           under qemu, slow, for what is about the kernel itself.
# `kernel` is host where it works, else vm: a kernel's vcan, never the
# user-space bus. The first line (on stderr) says which was chosen and why.
# When none works it fails (exit 125) and says why: SocketCAN tests never pass
# by skipping.
# --own-ipc: COMMAND runs in a System V IPC namespace of its own (unshare
# --ipc; as another user than root, inside a user namespace that maps that
# user to itself), so that the PMan tables and RTDB segments at a team's fixed
# keys it makes never meet another command's on this machine (the test suites
# run side by side). Inside the VM it has one anyway. Where the system allows
# neither, it says so and runs in the machine's.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ifaces=1
mode="${CANHIL_VCAN_MODE:-auto}"
own_ipc=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ifaces) ifaces="$2"; shift 2 ;;
    --mode) mode="$2"; shift 2 ;;
    --own-ipc) own_ipc=1; shift ;;
    --) shift; break ;;
    *) echo "with-vcan: unknown option $1 (put the command after --)" >&2; exit 125 ;;
  esac
done
case "$mode" in
  auto|host|user|vm|kernel) ;;
  *) echo "with-vcan: the mode is host, user, vm or kernel, not '$mode'" >&2; exit 125 ;;
esac

if [[ -n "${CANHIL_IN_VM:-}" ]]; then exec "$@"; fi  # already inside the VM

# What COMMAND runs inside on this machine: nothing, or an IPC namespace of its own.
isolate=()
if [[ $own_ipc -eq 1 ]]; then
  if unshare --ipc true 2>/dev/null; then
    isolate=(unshare --ipc)
  elif unshare --user --map-current-user --ipc true 2>/dev/null; then
    isolate=(unshare --user --map-current-user --ipc)
  else
    echo "with-vcan: no IPC namespace of its own here (unshare --ipc refused); running in the machine's" >&2
  fi
fi

find_canhil() {
  local c
  for c in "${CANHIL_BIN:-}" "$(command -v canhil 2>/dev/null || true)" "$here/../build/plain/app/canhil" \
           "$here/../../../bin/canhil"; do
    if [[ -n "$c" && -x "$c" ]]; then echo "$c"; return 0; fi
  done
  return 1
}

why_not_host=""
if [[ "$mode" == auto || "$mode" == host || "$mode" == kernel ]]; then
  if "$here/vcan-up.sh" "$ifaces" >/tmp/canhil-vcan-up.log 2>&1; then
    echo "with-vcan: host: running on this machine's vcan" >&2
    exec "${isolate[@]}" "$@"
  fi
  why_not_host="$(head -n 1 /tmp/canhil-vcan-up.log | sed "s/^vcan-up: //; s/[.]$//")"
  if [[ "$mode" == host ]]; then
    echo "with-vcan: host was asked for, but vcan cannot be set up here:" >&2
    cat /tmp/canhil-vcan-up.log >&2
    exit 125
  fi
fi

if [[ "$mode" == auto || "$mode" == user ]]; then
  if canhil="$(find_canhil)" && "$canhil" bus preload >/dev/null 2>&1; then
    names=""
    for ((i = 0; i < ifaces; i++)); do names+="${names:+,}vcan$i"; done
    echo "with-vcan: user: the kernel has no usable vcan${why_not_host:+ ($why_not_host)}; running natively on canhil's user-space bus" >&2
    exec "${isolate[@]}" "$canhil" bus exec --ifaces "$names" -- "$@"
  fi
  if [[ "$mode" == user ]]; then
    echo "with-vcan: user was asked for, but no canhil with its bus preload was found (set CANHIL_BIN, or build: scripts/build.sh plain)" >&2
    exit 125
  fi
fi

echo "with-vcan: vm: ${why_not_host:+the kernel has no usable vcan ($why_not_host); }running inside the VM runner" >&2
exec "$here/vm-run.sh" --ifaces "$ifaces" -- "$@"
