#!/usr/bin/env bash
# parallel_shards_test.sh BUILD_DIR — a batch split over "hosts" by GNU
# parallel (docs/teams.md), four shards of two seeds each, merged with
# `canhil match --report`, gives exactly the report of one --seeds run over the
# same eight seeds (wall times aside). One short half a match: cheap under the
# sanitizers too. Never skipped: GNU parallel is a test
# dependency (scripts/install-deps.sh).
set -euo pipefail
build=$1
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
canhil="$build/app/canhil"
command -v parallel > /dev/null || { echo "FAIL: GNU parallel is missing (apt-get install parallel)"; exit 1; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
match="$canhil match emulator/scenarios/two_teams.toml --halves 1 --half-minutes 0.02 --quiet --bit-rate 0"
# Two slots on this machine (':' is GNU parallel's name for it); across hosts
# the same line takes --sshlogin 4/node1,4/node2 and a shared folder.
parallel --will-cite --sshlogin 2/: "$match --jobs 1 --seeds {} --records $dir/shard{#}.jsonl > /dev/null" ::: 1..2 3..4 5..6 7..8
$match --seeds 1..8 --jobs 2 --records "$dir/one.jsonl" > /dev/null
"$canhil" match --report --json "$dir"/shard*.jsonl > "$dir/shards.json"
"$canhil" match --report --json "$dir/one.jsonl" > "$dir/one.json"
python3 - "$dir/shards.json" "$dir/one.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for r in (a, b):
    r.pop("wall_s")
if a != b:
    print("FAIL: the shards' report differs from one run's\n", json.dumps(a, indent=1), json.dumps(b, indent=1))
    sys.exit(1)
print(f"parallel shards: {a['matches']} matches in 4 shards, the same report as one run")
PY
