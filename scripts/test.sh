#!/usr/bin/env bash
# test.sh — the test command of the README: installs what is missing, then
# builds and runs the whole suite three times: plainly (g++ Release), with
# ASan + UBSan (clang, with libFuzzer smoke runs) and with ThreadSanitizer
# (clang), then the lint step.
# SocketCAN tests run on this machine's vcan or, where the kernel has no CAN,
# inside the VM runner; they never skip.
#   scripts/test.sh            every flavour, then the lint step
#   scripts/test.sh plain      one flavour (also: sanitize, tsan, lint)
# With lint and a flavour asked for, the lint step starts first, at idle
# priority (SCHED_IDLE): it takes only the CPU the builds and tests leave (the
# tests wait on the VM runner and on wall-clock timeouts much of their time)
# and never slows them; its verdict comes at the end, in the usual place.
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
stop_lint() { [[ -z "$lint_pid" ]] || kill -- "-$lint_pid" 2>/dev/null || true; }
trap stop_lint EXIT
start_lint() {
  local idle=(nice -n 19)
  chrt --idle 0 true 2>/dev/null && idle=(chrt --idle 0)
  mkdir -p build
  rm -f build/lint.status
  lint_start=$(date +%s)
  setsid bash -c '"$@" > build/lint.out 2>&1; echo $? > build/lint.status' lint \
    "${idle[@]}" bash scripts/lint.sh &
  lint_pid=$!
  echo "== canhil lint: started at idle priority beside the tests (its verdict comes last)"
}
total_start=$(date +%s)
SECONDS=0
[[ $early_lint -eq 1 ]] && start_lint
for flavour in "${flavours[@]}"; do
  if [[ "$flavour" == lint ]]; then
    echo "== canhil lint: clang-format, clang-tidy"
    if [[ -n "$lint_pid" ]]; then
      wait "$lint_pid" || true
      lint_pid=""
      cat build/lint.out
      stage "lint took (after the tests; $(( $(date +%s) - lint_start )) s since it started beside them)"
      [[ "$(cat build/lint.status 2>/dev/null)" == 0 ]] || exit 1
    else
      bash scripts/lint.sh
      stage "lint took"
    fi
    continue
  fi
  echo "== canhil tests: $flavour build"
  bash scripts/build.sh "$flavour"
  stage "$flavour build took"
  ctest --test-dir "build/$flavour" --output-on-failure -j2
  stage "$flavour tests took"
done
total=$(( $(date +%s) - total_start ))
printf '== canhil all stages took: %d min %d s\n' $((total / 60)) $((total % 60))
