#!/usr/bin/env bash
# run.sh — the viewer page's browser tests: Debian's chromium, headless,
# driven by puppeteer-core, against $CANHIL (the canhil binary; it serves its
# installed or built page, or $CANHIL_VIEWER_ROOT's). Screenshots go to
# $CANHIL_BROWSER_OUT (a temporary folder when unset); their paths are printed.
# Installs the npm packages first when they are missing (npm ci, from the
# committed locks); copying uPlot next to the page is the build's job.
# Exit status: non-zero when any test fails.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
web="$here/../../viewer/web"
: "${CANHIL:?set CANHIL to the canhil binary (e.g. build/dev/app/canhil)}"
export CANHIL
[[ -x "$CANHIL" ]] || { echo "run.sh: $CANHIL is not an executable" >&2; exit 2; }
[[ -n "${CANHIL_BROWSER_OUT:-}" ]] && export CANHIL_BROWSER_OUT

install() {  # folder, a file its packages provide
  if [[ ! -e "$1/node_modules/$2" || "$1/package-lock.json" -nt "$1/node_modules/.package-lock.json" ]]; then
    (cd "$1" && npm ci --no-audit --no-fund --loglevel=error)
  fi
}
install "$web" uplot/dist/uPlot.iife.min.js
install "$here" puppeteer-core/package.json

chromium="${CHROMIUM:-/usr/bin/chromium}"
[[ -x "$chromium" ]] || { echo "run.sh: $chromium is missing (apt-get install chromium; scripts/install-deps.sh does)" >&2; exit 2; }

# The tests' own WebSocket: node 22 has it; node 20 behind a flag (else the page's is used).
flags=()
if [[ "$(node -e 'process.stdout.write(typeof WebSocket)')" != function ]] &&
   node --experimental-websocket -e 0 2>/dev/null; then
  flags+=(--experimental-websocket)
fi

cd "$here"
exec node "${flags[@]}" --test --test-concurrency=1 live.test.mjs replay.test.mjs
