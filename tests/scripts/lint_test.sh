#!/usr/bin/env bash
# lint_test.sh SOURCE_DIR WORK_DIR — the lint step fails on a planted
# clang-tidy finding, again when the result comes from its cache, and passes
# a clean file: scripts/lint.sh as the test command runs it, on a compile
# database of files of its own, with the project's .clang-tidy.
# Then the batches: files with planted findings of both kinds of run (checks
# run over a batch of files compiled as one unit, and the static analyser and
# main-file checks file by file), two of them defining the same internal name
# (their batch does not compile as one unit), give the same findings batched
# as every check file by file gives (CANHIL_TIDY_BATCH=1).
set -euo pipefail
src=$1
work=$2
rm -rf "$work"
mkdir -p "$work/db" "$work/batch"
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
# In batches of three: b1 to b3 compile as one unit, with findings of batched
# checks in b1 and b3 and the analyser's in b1 and b2; b4 and b5 define the
# same internal name, so b4 to b6 are checked file by file (b6's finding).
cp "$work/planted.cpp" "$work/batch/b1.cpp"
cat > "$work/batch/b2.cpp" <<'CPP'
int b2(int a) {
  int* p = nullptr;
  if (a > 2) return *p;  // null dereference on one path
  return 0;
}
CPP
cat > "$work/batch/b3.cpp" <<'CPP'
namespace {
int helper(int x) { return x == x ? 1 : 0; }  // both sides equivalent
}  // namespace
int b3(int a) { return helper(a); }
CPP
cat > "$work/batch/b4.cpp" <<'CPP'
namespace {
int twice(int x) { return 2 * x; }
}  // namespace
int b4(int a) { return twice(a); }
CPP
cat > "$work/batch/b5.cpp" <<'CPP'
namespace {
int twice(int x) { return x + x; }
}  // namespace
int b5(int a) { return twice(a); }
CPP
cat > "$work/batch/b6.cpp" <<'CPP'
#include <vector>
int b6(const std::vector<int>& v) { return v.size() == 0 ? 1 : 0; }  // empty() would say it
CPP
{
  echo '['
  for f in planted clean; do
    echo "{\"directory\": \"$work\", \"file\": \"$f.cpp\", \"arguments\": [\"g++\", \"-std=c++20\", \"-c\", \"$f.cpp\", \"-o\", \"$f.o\"]},"
  done
  for i in 1 2 3 4 5 6; do
    sep=,; [[ $i == 6 ]] && sep=
    echo "{\"directory\": \"$work/batch\", \"file\": \"b$i.cpp\", \"arguments\": [\"g++\", \"-std=c++20\", \"-c\", \"b$i.cpp\", \"-o\", \"b$i.o\"]}$sep"
  done
  echo ']'
} > "$work/db/compile_commands.json"
# Its own cache, and the settings of lint.sh as a plain run has them (a developer
# may have turned the cache or the batches off in the environment).
export XDG_CACHE_HOME="$work/cache"
unset CANHIL_TIDY_CACHE CANHIL_TIDY_BATCH
lint() { bash "$src/scripts/lint.sh" --db "$work/db" --no-format --files "$1" > "$work/out.txt" 2>&1; }
fail() { echo "FAIL: $*"; cat "$work/out.txt"; exit 1; }

for pass in analysed cached; do
  if lint 'planted\.cpp'; then fail "lint passed a planted finding ($pass)"; fi
  grep -q "planted.cpp:6:.*bugprone-use-after-move" "$work/out.txt" || fail "the finding is not named ($pass)"
done
grep -q "1 file(s), 1 run(s) .*, 1 from the cache, 1 with findings" "$work/out.txt" ||
  fail "the second run did not come from the cache"
lint 'clean\.cpp' || fail "lint failed a clean file"
grep -q "clang-tidy clean" "$work/out.txt" || fail "no clean verdict"

# Every finding once, its file named the same way whichever run reported it.
findings() {
  grep -oE "^[^ ]*b[0-9]\.cpp:[0-9]+:[0-9]+: error: .*\[[A-Za-z.-]+" "$work/db/clang-tidy.log" |
    sed "s|^$work/batch/||" | sort -u > "$1" || true
}
if CANHIL_TIDY_BATCH=1 CANHIL_TIDY_CACHE=0 lint '/b[0-9]\.cpp'; then fail "lint passed the batch's findings file by file"; fi
grep -q "6 file(s), 6 run(s) (6 file by file, 0 of batched files)" "$work/out.txt" || fail "not file by file"
findings "$work/reference.txt"
for check in bugprone-use-after-move clang-analyzer-cplusplus.Move clang-analyzer-core.NullDereference \
             misc-redundant-expression readability-container-size-empty; do
  grep -q "\[$check" "$work/reference.txt" || { cat "$work/reference.txt"; fail "file by file did not find $check"; }
done
for pass in analysed cached; do
  if CANHIL_TIDY_BATCH=3 lint '/b[0-9]\.cpp'; then fail "lint passed the batch's findings ($pass)"; fi
  grep -q "6 file(s), 8 run(s) (6 file by file, 2 of batched files)" "$work/out.txt" ||
    fail "the files were not checked in two batches ($pass)"
  findings "$work/batched.txt"
  diff "$work/reference.txt" "$work/batched.txt" > "$work/diff.txt" ||
    { cat "$work/diff.txt"; fail "batched findings differ from file by file ($pass)"; }
done
grep -q "8 from the cache" "$work/out.txt" || fail "the batches' second run did not come from the cache"
echo "lint: a planted finding fails the step, analysed and from the cache; a clean file passes;" \
  "batches find what file by file finds ($(wc -l < "$work/reference.txt") findings in 6 files)"
