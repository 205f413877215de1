#!/usr/bin/env bash
# install_test.sh BUILD_DIR WORK_DIR — canhil installed into a temporary
# prefix, then moved elsewhere (an install must not remember where it was
# made): pkg-config and the CMake package must both give a team's program the
# installed headers and libraries (RTDB, librtdb.so, the access library and
# PMan), and the installed generator must work. CAMBADA's RTDB header names
# are at the include root, canhil's rtdb_user.h is not (a team's must win),
# and no installed header declares a global Vec.
set -euo pipefail
# No "producer | grep -q": grep -q leaves at the first match, the producer may
# then die of SIGPIPE, and pipefail fails the check. grep >/dev/null reads all.
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

echo "-- installed files"
for f in rtdb.h rtdb_api.h rtdb_sim.h rtdb_comm.h rtdbdefs.h canhil/rtdb/database.hpp canhil/rtdb/item_table.hpp \
         canhil/rtdb/replicator.hpp canhil/base/setup_error.hpp canhil/rtdb/shipped/rtdb_user.h; do
  [[ -f "$prefix/include/$f" ]] || { echo "FAIL: include/$f is not installed"; exit 1; }
done
[[ ! -e "$prefix/include/rtdb_user.h" ]] || { echo "FAIL: canhil's rtdb_user.h at the include root would hide a team's"; exit 1; }
librtdb=$(find "$prefix" -name librtdb.so | head -1)
[[ -n "$librtdb" ]] || { echo "FAIL: no librtdb.so installed"; exit 1; }
readelf -d "$librtdb" | grep 'SONAME.*\[librtdb.so\]' >/dev/null || { echo "FAIL: librtdb.so's soname is not librtdb.so"; exit 1; }
# Every installed header in one C++ unit with a Vec of its own (as CAMBADA code has).
{
  echo "struct Vec { double x, y, z; };"
  (cd "$prefix/include" && find . -name '*.h' -o -name '*.hpp' | sort | sed 's|^\./\(.*\)|#include "\1"|')
  echo "int main() { Vec v{1, 2, 3}; return v.x == 1 ? 0 : 1; }"
} > "$work/all_headers.cpp"
c++ -std=c++20 -fsyntax-only -I"$prefix/include" -I"$prefix/include/canhil/rtdb/shipped" "$work/all_headers.cpp" \
  || { echo "FAIL: the installed headers with a Vec of the program's own"; exit 1; }
echo "   $(grep -c '#include' "$work/all_headers.cpp") headers, no global Vec"

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

# A CAMBADA-style program: CAMBADA's header names, the team's rtdb_user.h, librtdb.so
# reading the team's rtdb.ini ($CANHIL_RTDB_INI), its own System V keys.
shared_flags=$(PKG_CONFIG_PATH=$pc_dir pkg-config --cflags --libs canhil-rtdb-shared)
echo "   $shared_flags"
# shellcheck disable=SC2086 # the flags are words
cc -o "$work/pc_cambada_agent" -I"$src/consumer/team" "$src/consumer/cambada_agent.c" $shared_flags
rtdb_key=$((0x5D000000 + ($$ & 0xFFFF) * 64))
run_agent() {
  RTDB_KEY=$rtdb_key AGENT=1 CANHIL_RTDB_INI="$src/consumer/team/rtdb.ini" "$@"
}
LD_LIBRARY_PATH=$lib run_agent "$work/pc_cambada_agent" | tee "$work/pc_agent.out"
grep -q "agent 1 of 2, CMD_VEL 16 bytes, read back vy 2.0, age fresh" "$work/pc_agent.out" \
  || { echo "FAIL: the CAMBADA-style program on librtdb.so (pkg-config)"; exit 1; }

echo "-- CMake package"
cmake -S "$src/consumer" -B "$work/consumer" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/shipped_items" | tee "$work/shipped.out"
grep -q "agents 7 items" "$work/shipped.out" || { echo "FAIL: shipped_items did not see canhil's items"; exit 1; }
"$work/consumer/team_items" | tee "$work/team.out"
grep -q "agents 3 items 2 first BALL_SEEN" "$work/team.out" || { echo "FAIL: team_items did not see the team's items"; exit 1; }
for p in pman_static pman_shared; do
  "$work/consumer/$p" | grep "pman table 246272 key 0x9013" >/dev/null || { echo "FAIL: $p (PMan through the CMake package)"; exit 1; }
done
ldd "$work/consumer/pman_shared" | grep "$prefix.*/libpman.so" >/dev/null || { echo "FAIL: pman_shared does not use the installed libpman.so"; exit 1; }
run_agent "$work/consumer/cambada_agent" | grep "agent 1 of 2, CMD_VEL 16 bytes" >/dev/null \
  || { echo "FAIL: cambada_agent (librtdb.so through the CMake package)"; exit 1; }
ldd "$work/consumer/cambada_agent" | grep "$prefix.*/librtdb.so" >/dev/null || { echo "FAIL: cambada_agent does not use the installed librtdb.so"; exit 1; }
"$work/consumer/team_table" "$src/consumer/team/rtdb_user.h" "$src/consumer/team/rtdb.ini" | tee "$work/table.out"
grep -q "team_table: 2 agents, CMD_VEL id 2, 16 bytes" "$work/table.out" || { echo "FAIL: team_table (the access library)"; exit 1; }
grep -q "$prefix" "$work/consumer/CMakeCache.txt" || { echo "FAIL: find_package did not use $prefix"; exit 1; }
for k in 0 1; do
  ipcs -m | grep -i "$(printf '0x%08x' $((rtdb_key + k)))" >/dev/null && { echo "FAIL: a System V segment was left behind"; exit 1; }
done
echo "install: relocatable, pkg-config and CMake package both work"
