#!/usr/bin/env bash
# install_test.sh BUILD_DIR WORK_DIR — canhil installed into a temporary
# prefix, then moved elsewhere (an install must not remember where it was
# made): pkg-config and the CMake package must both give a team's program the
# installed headers and libraries (RTDB and PMan), and the installed generator
# must work.
set -euo pipefail
build=$1
work=$2
src=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/first" >/dev/null
mv "$work/first" "$work/moved"
prefix=$work/moved
pc_dir=$(dirname "$(find "$prefix" -name canhil-rtdb.pc | head -1)")
[[ -n "$pc_dir" ]] || { echo "FAIL: no canhil-rtdb.pc installed"; exit 1; }

echo "-- pkg-config"
flags=$(PKG_CONFIG_PATH=$pc_dir pkg-config --cflags --libs canhil-rtdb)
echo "   $flags"
case "$flags" in *"$prefix"*) ;; *) echo "FAIL: pkg-config flags do not point into $prefix"; exit 1 ;; esac
lib=$(PKG_CONFIG_PATH=$pc_dir pkg-config --variable=libdir canhil-rtdb)
[[ -f "$lib/libcanhil_rtdb.a" ]] || { echo "FAIL: pkg-config's libdir $lib has no libcanhil_rtdb.a"; exit 1; }
# shellcheck disable=SC2086 # the flags are words
cc -o "$work/pc_consumer" "$src/consumer/main.c" $flags
"$work/pc_consumer" | tee "$work/pc.out"
grep -q "agents 7 items" "$work/pc.out" || { echo "FAIL: the pkg-config program did not see canhil's items"; exit 1; }

pman_flags=$(PKG_CONFIG_PATH=$pc_dir pkg-config --cflags --libs canhil-pman)
echo "   $pman_flags"
case "$pman_flags" in *"$prefix"*) ;; *) echo "FAIL: canhil-pman's flags do not point into $prefix"; exit 1 ;; esac
[[ -f "$lib/libcanhil_pman.a" && -f "$lib/libpman.so" ]] || { echo "FAIL: $lib lacks libcanhil_pman.a or libpman.so"; exit 1; }
# shellcheck disable=SC2086 # the flags are words
cc -o "$work/pc_pman" "$src/consumer/pman_main.c" $pman_flags
"$work/pc_pman" | tee "$work/pc_pman.out"
grep -q "pman table 246272 key 0x9013" "$work/pc_pman.out" || { echo "FAIL: the pkg-config PMan program"; exit 1; }

echo "-- CMake package"
cmake -S "$src/consumer" -B "$work/consumer" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/shipped_items" | tee "$work/shipped.out"
grep -q "agents 7 items" "$work/shipped.out" || { echo "FAIL: shipped_items did not see canhil's items"; exit 1; }
"$work/consumer/team_items" | tee "$work/team.out"
grep -q "agents 3 items 2 first BALL_SEEN" "$work/team.out" || { echo "FAIL: team_items did not see the team's items"; exit 1; }
for p in pman_static pman_shared; do
  "$work/consumer/$p" | grep -q "pman table 246272 key 0x9013" || { echo "FAIL: $p (PMan through the CMake package)"; exit 1; }
done
ldd "$work/consumer/pman_shared" | grep -q "$prefix.*/libpman.so" || { echo "FAIL: pman_shared does not use the installed libpman.so"; exit 1; }
grep -q "$prefix" "$work/consumer/CMakeCache.txt" || { echo "FAIL: find_package did not use $prefix"; exit 1; }
echo "install: relocatable, pkg-config and CMake package both work"
