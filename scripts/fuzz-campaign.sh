#!/usr/bin/env bash
# fuzz-campaign.sh — a long fuzzing campaign (CI runs only 20 s smoke runs):
# builds the libFuzzer targets optimised, with ASan + UBSan, into build/fuzz
# and runs each until it has executed RUNS inputs or MINUTES have passed,
# whichever comes first. New inputs go to build/fuzz/corpus-TARGET; crashes
# to build/fuzz/crash-TARGET-*. Prints each target's figures at the end.
#   scripts/fuzz-campaign.sh                 # every target, 10 000 000 runs or 30 min each
#   scripts/fuzz-campaign.sh dbc decode      # some targets
#   RUNS=1000000 MINUTES=5 scripts/fuzz-campaign.sh
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
runs=${RUNS:-10000000}
minutes=${MINUTES:-30}
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=($(ls fuzz/*_fuzz.cpp | sed 's|fuzz/||; s|_fuzz.cpp||'))
cmake -S . -B build/fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DCANHIL_SANITIZE=ON -DCANHIL_BUILD_TESTS=OFF -DCANHIL_BUILD_BENCH=OFF >/dev/null
cmake --build build/fuzz --target "${targets[@]/%/_fuzz}"
summary=()
for t in "${targets[@]}"; do
  work=build/fuzz/corpus-$t
  mkdir -p "$work"
  echo "== $t: up to $runs runs or $minutes min (corpus $work + fuzz/corpus/$t)"
  log=build/fuzz/$t.log
  status=0
  build/fuzz/fuzz/${t}_fuzz -runs="$runs" -max_total_time=$((minutes * 60)) -print_final_stats=1 \
    -artifact_prefix="build/fuzz/crash-$t-" "$work" "fuzz/corpus/$t" >"$log" 2>&1 || status=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 || echo "cov: ?")
  line="$t: $execs runs, $rate per s, $cov, exit $status"
  [[ $status -eq 0 ]] || line+=" (FINDING: see $log)"
  echo "   $line"
  summary+=("$line")
done
echo "== fuzz campaign"
printf '   %s\n' "${summary[@]}"
