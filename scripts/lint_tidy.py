#!/usr/bin/env python3
"""lint_tidy.py -p BUILD_DIR [--jobs N] [--cache DIR] [--root DIR] REGEX

clang-tidy over every file of BUILD_DIR/compile_commands.json whose path
matches REGEX (as run-clang-tidy does: the same checks from .clang-tidy, the
same arguments), with each file's result kept in a cache: a file whose
preprocessed text (itself and every header it includes, as clang sees them),
compile arguments, .clang-tidy files (its folder's and above) and clang-tidy
version are all unchanged
gives the findings it gave before without running the checks again. A second
clone of the same commit, or a change to one file, reruns only what changed.

The cache is in ${XDG_CACHE_HOME:-~/.cache}/canhil/clang-tidy (--cache DIR;
--cache '' turns it off), paths in it relative to the checkout (--root, the
folder holding .clang-tidy). Prints every finding; exit status 1 when a file
has one (WarningsAsErrors), 2 for a set-up mistake.
"""

import argparse
import concurrent.futures
import functools
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys

ROOT_MARK = "@CANHIL_ROOT@"


def arguments_of(entry):
    if "arguments" in entry:
        return list(entry["arguments"])
    return shlex.split(entry["command"])


def preprocess_arguments(args, file_name):
    """The compile's arguments turned into a clang preprocessing to stdout."""
    out = ["clang++" if file_name.endswith((".cpp", ".cc", ".cxx")) else "clang"]
    skip = False
    for a in args[1:]:
        if skip:
            skip = False
            continue
        if a in ("-o", "-MF", "-MT", "-MQ"):
            skip = True
            continue
        if a in ("-c", "-MD", "-MMD") or a.startswith(("-o", "-MF", "-MT")):
            continue
        out.append(a)
    return out + ["-E", "-Wno-unknown-warning-option", "-w"]


def tidy_version():
    return subprocess.run(["clang-tidy", "--version"], capture_output=True, text=True, check=True).stdout


@functools.lru_cache(maxsize=None)
def configs_above(folder):
    """The text of every .clang-tidy from `folder` up to /: what clang-tidy reads for a file there."""
    parent = os.path.dirname(folder)
    above = configs_above(parent) if parent != folder else ""
    path = os.path.join(folder, ".clang-tidy")
    if os.path.isfile(path):
        with open(path, encoding="utf-8") as f:
            return above + "\0" + path + "\n" + f.read()
    return above


def key_of(entry, file_name, root, salt):
    args = arguments_of(entry)
    pre = subprocess.run(preprocess_arguments(args, file_name), cwd=entry["directory"], capture_output=True)
    if pre.returncode != 0:
        return None  # clang-tidy will say what is wrong; never cached
    h = hashlib.sha256()
    h.update(salt.encode())
    h.update(configs_above(os.path.dirname(os.path.realpath(file_name))).replace(root, ROOT_MARK).encode())
    h.update("\0".join(args).replace(root, ROOT_MARK).encode())
    h.update(entry["directory"].replace(root, ROOT_MARK).encode())
    h.update(pre.stdout.replace(root.encode(), ROOT_MARK.encode()))
    return h.hexdigest()


def run_tidy(build_dir, file_name):
    r = subprocess.run(["clang-tidy", "-p", build_dir, "-quiet", "-extra-arg=-Wno-unknown-warning-option", file_name],
                       capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def lint_one(entry, build_dir, root, salt, cache):
    file_name = os.path.join(entry["directory"], entry["file"])
    key = key_of(entry, file_name, root, salt) if cache else None
    path = os.path.join(cache, key[:2], key) if key else None
    if path and os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            stored = json.load(f)
        return file_name, stored["status"], stored["output"].replace(ROOT_MARK, root), True
    status, output = run_tidy(build_dir, file_name)
    if path:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        temporary = path + ".%d" % os.getpid()
        with open(temporary, "w", encoding="utf-8") as f:
            json.dump({"status": status, "output": output.replace(root, ROOT_MARK)}, f)
        os.replace(temporary, path)
    return file_name, status, output, False


def main():
    default_cache = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "canhil",
                                 "clang-tidy")
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[1], usage=__doc__.split("\n")[0])
    p.add_argument("-p", dest="build_dir", required=True)
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--cache", default=default_cache)
    p.add_argument("--root", default=os.getcwd())
    p.add_argument("regex")
    o = p.parse_args()
    database = os.path.join(o.build_dir, "compile_commands.json")
    try:
        with open(database, encoding="utf-8") as f:
            entries = json.load(f)
    except (OSError, ValueError) as e:
        print("lint_tidy: cannot read %s (%s): build first (scripts/build.sh plain)" % (database, e), file=sys.stderr)
        return 2
    root = os.path.realpath(o.root)
    pattern = re.compile(o.regex)
    chosen, seen = [], set()
    for e in entries:
        name = os.path.join(e["directory"], e["file"])
        if pattern.search(name) and name not in seen:
            seen.add(name)
            chosen.append(e)
    if not chosen:
        print("lint_tidy: no file of %s matches %s" % (database, o.regex), file=sys.stderr)
        return 2
    salt = tidy_version()
    failed, reused = 0, 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, o.jobs)) as pool:
        for file_name, status, output, cached in pool.map(
                lambda e: lint_one(e, o.build_dir, root, salt, o.cache), chosen):
            reused += cached
            if status != 0:
                failed += 1
                sys.stdout.write(output if output.endswith("\n") or not output else output + "\n")
    print("lint_tidy: %d file(s), %d from the cache, %d with findings" % (len(chosen), reused, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
