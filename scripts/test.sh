#!/usr/bin/env bash
# test.sh — the test command of the README: installs what is missing, then
# builds and runs the whole suite three times: plainly (g++ Release), with
# ASan + UBSan (clang, with libFuzzer smoke runs) and with ThreadSanitizer
# (clang), then the lint step.
# SocketCAN tests run on this machine's vcan or, where the kernel has no CAN,
# inside the VM runner; they never skip.
#   scripts/test.sh            every flavour, then the lint step
#   scripts/test.sh plain      one flavour (also: sanitize, tsan, lint)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
bash scripts/install-deps.sh
flavours=("$@")
[[ ${#flavours[@]} -gt 0 ]] || flavours=(plain sanitize tsan lint)
# Each stage's wall time, so CI's log shows where its minutes go.
stage() { printf '== canhil %s: %d min %d s\n' "$1" $((SECONDS / 60)) $((SECONDS % 60)); SECONDS=0; }
SECONDS=0
for flavour in "${flavours[@]}"; do
  if [[ "$flavour" == lint ]]; then
    echo "== canhil lint: clang-format, clang-tidy"
    bash scripts/lint.sh
    stage "lint took"
    continue
  fi
  echo "== canhil tests: $flavour build"
  bash scripts/build.sh "$flavour"
  stage "$flavour build took"
  ctest --test-dir "build/$flavour" --output-on-failure -j2
  stage "$flavour tests took"
done
