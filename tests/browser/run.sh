#!/usr/bin/env bash
# run.sh — the viewer's browser tests: installs puppeteer-core from npm when
# missing, then runs the tests in Debian's chromium, headless, against
# $CANHIL (the canhil binary). Screenshots go to $CANHIL_BROWSER_OUT.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"
: "${CANHIL:?set CANHIL to the canhil binary}"
if [[ ! -d node_modules/puppeteer-core || package-lock.json -nt node_modules ]]; then
  npm ci --no-audit --no-fund --loglevel=error >/dev/null
  touch node_modules
fi
[[ -x /usr/bin/chromium ]] || { echo "run.sh: /usr/bin/chromium is missing (apt-get install chromium; scripts/install-deps.sh does)" >&2; exit 2; }
exec node --test --test-concurrency=1 viewer.test.mjs
