#!/usr/bin/env bash
# lint_test.sh SOURCE_DIR WORK_DIR — the lint step fails on a planted
# clang-tidy finding, again when the result comes from its cache, and passes
# a clean file: scripts/lint.sh as the test command runs it, on a compile
# database of two files of its own, with the project's .clang-tidy.
set -euo pipefail
src=$1
work=$2
rm -rf "$work"
mkdir -p "$work/db"
cp "$src/.clang-tidy" "$work/"
cat > "$work/planted.cpp" <<'CPP'
#include <string>
#include <utility>

int planted(std::string s) {
  std::string t = std::move(s);
  return static_cast<int>(s.size() + t.size());  // s read after it was moved from
}
CPP
cat > "$work/clean.cpp" <<'CPP'
#include <string>
#include <utility>

int clean(std::string s) {
  std::string t = std::move(s);
  return static_cast<int>(t.size());
}
CPP
cat > "$work/db/compile_commands.json" <<JSON
[{"directory": "$work", "file": "planted.cpp", "arguments": ["g++", "-std=c++20", "-c", "planted.cpp", "-o", "planted.o"]},
 {"directory": "$work", "file": "clean.cpp", "arguments": ["g++", "-std=c++20", "-c", "clean.cpp", "-o", "clean.o"]}]
JSON
export XDG_CACHE_HOME="$work/cache"
lint() { bash "$src/scripts/lint.sh" --db "$work/db" --no-format --files "$1" > "$work/out.txt" 2>&1; }
fail() { echo "FAIL: $*"; cat "$work/out.txt"; exit 1; }

for pass in analysed cached; do
  if lint 'planted\.cpp'; then fail "lint passed a planted finding ($pass)"; fi
  grep -q "planted.cpp:6:.*bugprone-use-after-move" "$work/out.txt" || fail "the finding is not named ($pass)"
done
grep -q "1 file(s), 1 from the cache, 1 with findings" "$work/out.txt" || fail "the second run did not come from the cache"
lint 'clean\.cpp' || fail "lint failed a clean file"
grep -q "clang-tidy clean" "$work/out.txt" || fail "no clean verdict"
echo "lint: a planted finding fails the step, analysed and from the cache; a clean file passes"
