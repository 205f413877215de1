#!/usr/bin/env bash
# run-own-software.sh — a team's laptop software against canhil, all three
# together (docs/own-software.md): `canhil run` with the team's RTDB and PMan
# libraries and layout, `canhil-hwcomm` as the robot's handler on the same
# RTDB, and the team's agent. Ctrl-C (or the agent ending) stops them in
# order: the handler, then the run (which closes the PMan tables: the agent
# gets SIGINT), and prints the run's summary; each by SIGTERM, and SIGKILL
# if it has not ended within 10 s, so the script ends whatever state they
# are in. An agent that fails (ends by itself with a non-zero status) ends
# the script with status 1, after the end of its log. The run lasts until then, or
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

# Ends one process of ours and waits for it, whatever its start-up state:
# SIGTERM, which canhil and canhil-hwcomm take as Ctrl-C (a background job of
# a script starts with SIGINT ignored, so a SIGINT sent before the program
# installs its handler would be lost), then SIGKILL if it has not ended
# within $2 seconds (default 10). Never hangs.
end_process() {
  kill -TERM "$1" 2>/dev/null || true
  wait_end "$1" "${2:-10}"
  kill -KILL "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}
# Waits up to $2 seconds for process $1 to end (gone, or a zombie not yet reaped).
wait_end() {
  local k state
  for ((k = 0; k < $2 * 10; k++)); do
    state=$(sed 's/.*) \(.\).*/\1/' "/proc/$1/stat" 2>/dev/null) || return 0
    [[ "$state" == Z ]] && return 0
    sleep 0.1
  done
}

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
  end_process "$run_pid"
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
  end_process "$hw_pid"
  end_process "$run_pid"  # it closes the PMan tables: the agent gets SIGINT
  wait_end "$agent_pid" 2
  end_process "$agent_pid" 2
  echo "== canhil run's summary"
  sed -n '/^canhil run: \(done\|stopped\) after/,$p' "$logs/run.log"
}
trap stop INT TERM
echo "== running; Ctrl-C stops all three (canhil coach stop|start, canhil pman list meanwhile)"
agent_status=0
wait "$agent_pid" || agent_status=$?
if [[ $stopped == 0 && $agent_status -ne 0 ]]; then
  # The agent ended by itself, failing: say so, stop the rest, and end as it did.
  echo "== the agent ended with status $agent_status; the end of its log ($logs/agent.log):"
  tail -n 5 "$logs/agent.log" | sed 's/^/   /'
  stop
  exit 1
fi
stop
