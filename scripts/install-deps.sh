#!/usr/bin/env bash
# install-deps.sh [main|all] — the system packages canhil needs, from Debian's
# archive: `main` what the main job needs to build canhil and run it (the
# compiler, the libraries, can-utils and the VM runner), `all` (the default)
# also what the tests need (clang and its sanitizer runtime, the linters,
# canmatrix, chromium). Idempotent and quick when everything is there.
# Needs root (apt-get); CI and the developers' machines run as root.
set -euo pipefail

set_of="${1:-all}"
[[ "$set_of" == main || "$set_of" == all ]] || { echo "install-deps: takes main or all, not $set_of" >&2; exit 2; }
packages=(
  # build (ccache and mold speed it up; scripts/build.sh uses them where installed)
  cmake ninja-build g++ pkg-config ccache mold
  libgtest-dev libgmock-dev libbenchmark-dev
  # physics
  libode-dev libeigen3-dev libtomlplusplus-dev
  # the control channel and the viewer: JSON, HTTP and WebSocket
  nlohmann-json3-dev libboost-dev
  # SocketCAN tools and interface set-up
  can-utils iproute2 kmod
  # the VM runner for kernels without CAN (vcan_setup/vm-run.sh)
  qemu-system-x86 linux-image-amd64 busybox-static cpio
)
if [[ "$set_of" == all ]]; then
  packages+=(
    # the sanitized flavours and the lint step
    clang libclang-rt-14-dev clang-format clang-tidy
    # independent DBC decoder for the cross-check tests
    python3 python3-canmatrix python3-can
    # the viewer's browser tests (headless, driven by puppeteer-core from npm)
    chromium
    # canhil test --junit checked against Jenkins' JUnit schema (tests/app/test_command_test.sh);
    # the Debian package built by CPack, its man pages and docs/ci.md's YAML checked (tests/install/deb_test.sh)
    libxml2-utils dpkg-dev file groff-base python3-yaml
    # canhil match split over hosts, as docs/teams.md shows (tests/app/parallel_shards_test.sh)
    parallel
    # a busy machine beside the tests (CANHIL_TEST_LOAD=1 scripts/test.sh, docs/testing.md)
    stress-ng
  )
fi

# The viewer's page takes its one library (uPlot) from npm; the build copies it next to the page.
npm_install() {
  local dir="$1"
  if [[ ! -d "$dir/node_modules" || "$dir/package-lock.json" -nt "$dir/node_modules" ]]; then
    command -v npm >/dev/null || { echo "install-deps: npm is missing (Node.js with npm)" >&2; exit 2; }
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
    touch "$dir/node_modules"
  fi
}

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -gt 0 ]]; then
  if [[ $(id -u) -ne 0 ]]; then
    echo "install-deps: missing ${missing[*]}; run as root: apt-get update && apt-get install ${missing[*]}" >&2
    exit 2
  fi
  echo "install-deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
cd "$(dirname "${BASH_SOURCE[0]}")/.."
npm_install viewer/web
