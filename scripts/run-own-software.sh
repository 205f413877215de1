#!/usr/bin/env bash
# run-own-software.sh — a team's laptop software against canhil, all three
# together (docs/own-software.md): `canhil run` with the team's RTDB and PMan
# libraries and layout, `canhil-hwcomm` as the robot's handler on the same
# RTDB, and the team's agent. Ctrl-C (or the agent ending) stops them in
# order: the handler, then the run (which closes the PMan tables: the agent
# gets SIGINT), and prints the run's summary. The run lasts until then, or
# --duration S seconds (the scenario's duration_s is not used here). Logs go to --logs (default
# ./canhil-own-software/).
#
#   scripts/run-own-software.sh [--canhil DIR] [--config SCENARIO.toml] [--iface vcan0] [--agent-number 1]
#       [--rtdb-lib LIB --rtdb-items RTDB_USER_H --rtdb-ini RTDB_INI] [--layout cambada|canhil|FILE]
#       [--pman-lib LIB] [--agent-dir DIR] [--logs DIR] [--duration S] -- AGENT_COMMAND [ARG...]
#
# --canhil: the folder with canhil's programs (app/canhil and laptop/canhil-hwcomm
# of a build, or an installed bin/); default build/plain, else what is on PATH.
# --agent-dir: where the agent starts (a CAMBADA agent reads ../config/).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
die() { echo "run-own-software.sh: $*" >&2; exit 2; }

canhil_dir="" config="" duration=0 iface=vcan0 agent=1 layout="" pman_lib="" agent_dir="" logs="$PWD/canhil-own-software"
rtdb=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --canhil) canhil_dir=$2; shift 2 ;;
    --config) config=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --iface) iface=$2; shift 2 ;;
    --agent-number) agent=$2; shift 2 ;;
    --rtdb-lib|--rtdb-items|--rtdb-ini) rtdb+=("$1" "$2"); shift 2 ;;
    --layout) layout=$2; shift 2 ;;
    --pman-lib) pman_lib=$2; shift 2 ;;
    --agent-dir) agent_dir=$2; shift 2 ;;
    --logs) logs=$2; shift 2 ;;
    --) shift; break ;;
    *) die "unknown option $1 (see the comment at the top of this script)" ;;
  esac
done
[[ $# -gt 0 ]] || die "give the agent's command after --, e.g. -- ./agent"

find_program() {  # NAME SUBDIR: the program in --canhil, the build, or on PATH
  local name=$1 sub=$2
  for d in "$canhil_dir" "$canhil_dir/$sub" "$here/build/plain/$sub"; do
    [[ -n "$d" && -x "$d/$name" ]] && { echo "$d/$name"; return; }
  done
  command -v "$name" || die "cannot find $name: build canhil (scripts/build.sh plain) or give --canhil DIR"
}
canhil=$(find_program canhil app)
hwcomm=$(find_program canhil-hwcomm laptop)

laptop=("${rtdb[@]}")
[[ -n "$layout" ]] && laptop+=(--layout "$layout")
run_args=(run)
[[ -n "$config" ]] && run_args+=(--config "$config")
run_args+=(--duration "$duration")  # 0: until Ctrl-C
run_args+=("${laptop[@]}")
[[ -n "$pman_lib" ]] && run_args+=(--pman-lib "$pman_lib")

mkdir -p "$logs"
export AGENT=$agent
echo "== canhil run (log: $logs/run.log)"
"$canhil" "${run_args[@]}" >"$logs/run.log" 2>&1 &
run_pid=$!
started=""
for _ in $(seq 100); do
  grep -q "robot [0-9]* on " "$logs/run.log" 2>/dev/null && { started=1; break; }
  kill -0 "$run_pid" 2>/dev/null || { cat "$logs/run.log"; die "canhil run ended before it started"; }
  sleep 0.1
done
# The scenario decides the run's interfaces and agent numbers: the handler and
# the agent must be started on the ones it uses.
if [[ -z "$started" ]] || ! grep -qE "on $iface( \([^)]*\))? for agent $agent " "$logs/run.log"; then
  kill -INT "$run_pid" 2>/dev/null || true
  wait "$run_pid" 2>/dev/null || true
  grep "robot [0-9]* on " "$logs/run.log" >&2 || cat "$logs/run.log" >&2
  die "canhil run has no robot on $iface for agent $agent (above: what it runs); give --iface and --agent-number as its scenario says, or a --config whose [run] interfaces and agents say so"
fi
echo "== canhil-hwcomm on $iface, agent $agent (log: $logs/hwcomm.log)"
"$hwcomm" --iface "$iface" "${laptop[@]}" >"$logs/hwcomm.log" 2>&1 &
hw_pid=$!
echo "== the agent: $* (log: $logs/agent.log)"
(
  [[ -n "$agent_dir" ]] && cd "$agent_dir"
  exec "$@"
) >"$logs/agent.log" 2>&1 &
agent_pid=$!

stopped=0
stop() {
  [[ $stopped == 0 ]] || return 0
  stopped=1
  trap - INT TERM
  kill -INT "$hw_pid" 2>/dev/null || true
  wait "$hw_pid" 2>/dev/null || true
  kill -INT "$run_pid" 2>/dev/null || true
  wait "$run_pid" 2>/dev/null || true
  sleep 0.5
  kill "$agent_pid" 2>/dev/null || true
  wait "$agent_pid" 2>/dev/null || true
  echo "== canhil run's summary"
  sed -n '/^canhil run: \(done\|stopped\) after/,$p' "$logs/run.log"
}
trap stop INT TERM
echo "== running; Ctrl-C stops all three (canhil coach stop|start, canhil pman list meanwhile)"
wait "$agent_pid" || true
stop
