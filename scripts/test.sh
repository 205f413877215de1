#!/usr/bin/env bash
# test.sh — the test command of the README: installs what is missing, then
# builds and runs the whole suite three times: plainly (g++ Release), with
# ASan + UBSan (clang, with libFuzzer smoke runs) and with ThreadSanitizer
# (clang), then the lint step.
# SocketCAN tests run on this machine's vcan or, where the kernel has no CAN,
# inside the VM runner; they never skip.
#   scripts/test.sh            every flavour, then the lint step
#   scripts/test.sh plain      one flavour (also: sanitize, tsan, lint)
#   CANHIL_TEST_LOAD=1 scripts/test.sh [FLAVOUR...]
#                              the same with a busy machine beside it: Debian's
#                              stress-ng --cpu 4 --vm 1 --vm-bytes 256M (about
#                              what a parallel build does to a 2-core machine)
#                              runs from the first build to the end, so that a
#                              test that holds only on an idle machine shows
#                              here and not on a shared CI runner; any other
#                              value is stress-ng's arguments (docs/testing.md)
# With lint and a flavour asked for, the lint step starts after the first
# build, at idle priority (SCHED_IDLE), and runs while the tests run (they
# wait on the VM runner and on wall-clock timeouts much of their time, and
# leave most of the CPU); it is paused (SIGSTOP) while a build runs, so a
# build's time is its own; its verdict comes at the end, in the usual place.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
flavours=("$@")
[[ ${#flavours[@]} -gt 0 ]] || flavours=(plain sanitize tsan lint)
early_lint=0
[[ ${#flavours[@]} -gt 1 && " ${flavours[*]} " == *" lint "* ]] && early_lint=1
# Each stage's wall time, so CI's log shows where its minutes go.
stage() { printf '== canhil %s: %d min %d s\n' "$1" $((SECONDS / 60)) $((SECONDS % 60)); SECONDS=0; }
lint_pid=""
stop_lint() { [[ -z "$lint_pid" ]] || kill -CONT -- "-$lint_pid" 2>/dev/null; [[ -z "$lint_pid" ]] || kill -- "-$lint_pid" 2>/dev/null || true; }
pause_lint() { [[ -z "$lint_pid" ]] || kill -STOP -- "-$lint_pid" 2>/dev/null || true; }
resume_lint() { [[ -z "$lint_pid" ]] || kill -CONT -- "-$lint_pid" 2>/dev/null || true; }
start_lint() {
  local idle=(nice -n 19)
  chrt --idle 0 true 2>/dev/null && idle=(chrt --idle 0)
  mkdir -p build
  rm -f build/lint.status
  lint_start=$(date +%s)
  setsid bash -c '"$@" > build/lint.out 2>&1; echo $? > build/lint.status' lint \
    "${idle[@]}" bash scripts/lint.sh &
  lint_pid=$!
  echo "== canhil lint: started at idle priority beside the tests, paused during builds (its verdict comes last)"
}
load_pid=""
stop_load() { [[ -z "$load_pid" ]] || kill -- "-$load_pid" 2>/dev/null || true; }
trap 'stop_lint; stop_load' EXIT
if [[ -n "${CANHIL_TEST_LOAD:-}" ]]; then
  load_args=(--cpu 4 --vm 1 --vm-bytes 256M)
  [[ "$CANHIL_TEST_LOAD" == 1 ]] || read -r -a load_args <<< "$CANHIL_TEST_LOAD"
  setsid stress-ng "${load_args[@]}" --timeout 0 > /dev/null 2>&1 &
  load_pid=$!
  echo "== canhil tests: with stress-ng ${load_args[*]} beside them (CANHIL_TEST_LOAD)"
fi
total_start=$(date +%s)
SECONDS=0
for flavour in "${flavours[@]}"; do
  if [[ "$flavour" == lint ]]; then
    echo "== canhil lint: clang-format, clang-tidy"
    if [[ -n "$lint_pid" ]]; then
      resume_lint
      wait "$lint_pid" || true
      lint_pid=""
      cat build/lint.out
      stage "lint took (after the tests; $(( $(date +%s) - lint_start )) s since it started beside them, builds included)"
      [[ "$(cat build/lint.status 2>/dev/null)" == 0 ]] || exit 1
    else
      bash scripts/lint.sh
      stage "lint took"
    fi
    continue
  fi
  echo "== canhil tests: $flavour build"
  pause_lint
  bash scripts/build.sh "$flavour"
  stage "$flavour build took"
  if [[ $early_lint -eq 1 && -z "$lint_pid" ]]; then start_lint; else resume_lint; fi
  ctest --test-dir "build/$flavour" --output-on-failure -j2
  stage "$flavour tests took"
done
total=$(( $(date +%s) - total_start ))
printf '== canhil all stages took: %d min %d s\n' $((total / 60)) $((total % 60))
