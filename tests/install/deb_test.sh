#!/usr/bin/env bash
# deb_test.sh BUILD_DIR WORK_DIR — canhil's Debian package as a team's CI
# gets it: built by CPack from this build (canhil_VERSION_amd64.deb), its
# dependencies worked out from the shared libraries it links, then unpacked
# with dpkg-deb -x into a folder of its own (nothing installed on this
# machine) and run from there: `canhil test` on the shipped examples passes,
# also with the reference programs as processes on canhil's user-space bus
# (the packaged preloads), and every program has its man page.
set -euo pipefail
build=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*" >&2; exit 1; }
# A user-space bus of this test's own (`canhil bus exec` joins one that runs at its folder); ci_doc_test's commands inherit it.
export CANHIL_BUS_DIR="$work/bus"
(cd "$build" && cpack -G DEB -B "$work/pack" > "$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; fail "cpack"; }
version=$(sed -n 's/^project(canhil VERSION \([0-9.]*\).*/\1/p' "$(dirname "${BASH_SOURCE[0]}")/../../CMakeLists.txt")
deb="$work/pack/canhil_${version}_amd64.deb"
[[ -f "$deb" ]] || { ls "$work/pack"; fail "no $deb"; }
info=$(dpkg-deb -I "$deb")
for dep in libode8 libtomlplusplus3 libstdc++6 libc6; do
  grep -q "Depends:.*$dep" <<<"$info" || { echo "$info"; fail "Depends lacks $dep"; }
done
grep -q "Package: canhil" <<<"$info" || fail "not named canhil"
contents=$(dpkg-deb -c "$deb")
for f in ./usr/bin/canhil ./usr/bin/canhil-hwcomm ./usr/bin/canhil-agent ./usr/bin/canhil-rtdb-gen \
         ./usr/lib/libcanhil-timeshim.so ./usr/lib/libcanhil-bus.so ./usr/lib/librtdb.so ./usr/lib/libpman.so \
         ./usr/share/canhil/canhil.dbc ./usr/share/canhil/layouts/cambada.toml ./usr/share/canhil/viewer/index.html \
         ./usr/share/canhil/scenarios/one_robot.toml ./usr/share/canhil/scenarios/tests/score.toml \
         ./usr/share/doc/canhil/testing-your-software.md ./usr/share/doc/canhil/ci.md ./usr/share/doc/canhil/README.md \
         ./usr/share/man/man1/canhil.1 ./usr/share/man/man1/canhil-hwcomm.1 ./usr/share/man/man1/canhil-agent.1 \
         ./usr/share/man/man1/canhil-rtdb-gen.1; do
  grep -q " $f\$" <<<"$contents" || fail "the package lacks $f"
done
root="$work/root"
dpkg-deb -x "$deb" "$root"
for page in canhil canhil-hwcomm canhil-agent canhil-rtdb-gen; do
  warnings=$(groff -man -Tutf8 -ww "$root/usr/share/man/man1/$page.1" 2>&1 >/dev/null)
  [[ -z "$warnings" ]] || fail "$page.1: $warnings"
done
cd "$work"
status=0
"$root/usr/bin/canhil" test "$root"/usr/share/canhil/scenarios/tests/*.toml --junit report.xml > test.txt 2>&1 || status=$?
[[ $status -eq 0 ]] || { cat test.txt; fail "the unpacked canhil test: exit $status"; }
grep -q "0 failed, 0 file(s) with errors" test.txt || { cat test.txt; fail "no passing summary"; }
grep -q "<testsuites" report.xml || fail "no JUnit report"
status=0
PATH="$root/usr/bin:$PATH" "$root/usr/bin/canhil" bus exec -- "$root/usr/bin/canhil" test \
  "$root/usr/share/canhil/scenarios/tests/processes/score.toml" > processes.txt 2>&1 || status=$?
[[ $status -eq 0 ]] || { cat processes.txt; fail "the unpacked canhil test with processes: exit $status"; }
# docs/ci.md's recipes, run with this package (tests/install/ci_doc_test.py).
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
/usr/bin/python3 "$here/ci_doc_test.py" "$here/../../docs/ci.md" "$deb" "$here/team_repo" "$work/ci" ||
  fail "docs/ci.md's recipes"
echo "deb_test: $(basename "$deb") ($(stat -c %s "$deb") bytes) built, unpacked and run"
