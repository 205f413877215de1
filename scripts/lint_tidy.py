#!/usr/bin/env python3
"""lint_tidy.py -p BUILD_DIR [--jobs N] [--batch N] [--cache DIR] [--root DIR] REGEX

clang-tidy over every file of BUILD_DIR/compile_commands.json whose path
matches REGEX, with the checks .clang-tidy enables for it and the findings
file by file would give, in two kinds of run:

- file by file, the checks whose verdict depends on which file is the main
  one or on the whole translation unit: the static analyser (clang-analyzer-*
  analyses the main file's functions only), misc-unused-using-decls (main file
  only), bugprone-suspicious-include (an #include of a .cpp), and the checks
  that follow calls or collect over the unit (bugprone-exception-escape,
  -signal-handler, -forward-declaration-namespace, -argument-comment);
- every other check once over a batch of up to --batch files (default 32)
  that share compile arguments and configuration, included one after the other
  in a generated file, the batch's own files added to the header filter so
  their findings are reported as file by file reports them. These checks match
  every declaration of the unit, system headers included: a batch walks the
  headers once where file by file walks them once per file. A batch that does
  not compile as one unit (two files define the same internal name) is checked
  file by file instead.
--batch 1: every check file by file (the reference the batches are tested against).

Each run's result is kept in a cache: a run whose files' preprocessed text
(each file and every header it includes, as clang sees them), compile
arguments, .clang-tidy files (its folder's and above), checks and clang-tidy
version are all unchanged gives the findings it gave before without running
the checks again. A second clone of the same commit, or a change to one file,
reruns only what changed.

The cache is in ${XDG_CACHE_HOME:-~/.cache}/canhil/clang-tidy (--cache DIR;
--cache '' turns it off), paths in it relative to the checkout (--root, the
folder holding .clang-tidy). Prints every finding; exit status 1 when a run has
one (WarningsAsErrors), 2 for a set-up mistake.
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
TIDY = ["clang-tidy", "-quiet", "-extra-arg=-Wno-unknown-warning-option"]
# Checks run file by file (see the module's text); every clang-analyzer-* too.
WHOLE_UNIT_CHECKS = frozenset({
    "misc-unused-using-decls", "bugprone-suspicious-include", "bugprone-exception-escape",
    "bugprone-signal-handler", "bugprone-forward-declaration-namespace", "bugprone-argument-comment"})


def arguments_of(entry):
    if "arguments" in entry:
        return list(entry["arguments"])
    return shlex.split(entry["command"])


def source_of(entry):
    return os.path.normpath(os.path.join(entry["directory"], entry["file"]))


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


def arguments_without_source(entry):
    """The compile's arguments with its source and output left out: what files of one batch share."""
    source, out, skip = source_of(entry), [], False
    for a in arguments_of(entry)[1:]:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a in (entry["file"], source):
            continue
        out.append(a)
    return [arguments_of(entry)[0]] + out


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


def config_of(file_name):
    return configs_above(os.path.dirname(os.path.realpath(file_name)))


def text_key(entry, root):
    """What decides a file's findings apart from the checks: its preprocessed text, arguments,
    folder and configuration (None when it does not preprocess; such a run is never cached)."""
    file_name = source_of(entry)
    args = arguments_of(entry)
    pre = subprocess.run(preprocess_arguments(args, file_name), cwd=entry["directory"], capture_output=True)
    if pre.returncode != 0:
        return None
    h = hashlib.sha256()
    h.update(config_of(file_name).replace(root, ROOT_MARK).encode())
    h.update("\0".join(args).replace(root, ROOT_MARK).encode())
    h.update(entry["directory"].replace(root, ROOT_MARK).encode())
    h.update(pre.stdout.replace(root.encode(), ROOT_MARK.encode()))
    return h.hexdigest()


def enabled_checks(build_dir, file_name):
    """The checks the configuration enables for this file, and its header filter."""
    listed = subprocess.run(TIDY + ["-p", build_dir, "--list-checks", file_name], capture_output=True, text=True)
    dumped = subprocess.run(TIDY + ["-p", build_dir, "--dump-config", file_name], capture_output=True, text=True)
    if listed.returncode != 0 or dumped.returncode != 0:
        raise RuntimeError("clang-tidy cannot read its configuration for %s: %s" %
                           (file_name, (listed.stderr + dumped.stderr).strip()))
    checks = [line.strip() for line in listed.stdout.splitlines()[1:] if line.strip()]
    m = re.search(r"^HeaderFilterRegex:\s*'(.*)'\s*$", dumped.stdout, re.M)
    return checks, (m.group(1).replace("''", "'") if m else "")


def whole_unit(check):
    return check.startswith("clang-analyzer-") or check in WHOLE_UNIT_CHECKS


class Run:
    """One clang-tidy run: one file, or a batch of files included into one generated unit."""

    def __init__(self, entries, checks, header_filter=None, unit=None):
        self.entries, self.checks, self.header_filter, self.unit = entries, checks, header_filter, unit

    def command(self, build_dir):
        cmd = TIDY + ["-p", build_dir, "--checks=-*," + ",".join(self.checks)]
        if self.unit:
            return cmd + ["--header-filter=" + self.header_filter, self.unit]
        return cmd + [source_of(self.entries[0])]

    def key(self, keys, salt, root):
        if any(keys[source_of(e)] is None for e in self.entries):
            return None
        h = hashlib.sha256()
        for part in [salt, "unit" if self.unit else "file", ",".join(self.checks), self.header_filter or ""]:
            h.update(part.replace(root, ROOT_MARK).encode() + b"\0")
        for e in self.entries:
            h.update(keys[source_of(e)].encode())
        return h.hexdigest()


def run_tidy(build_dir, unit_dir, run):
    r = subprocess.run(run.command(unit_dir if run.unit else build_dir), capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def plan(chosen, build_dir, batch, unit_dir):
    """The runs that check every chosen file: file by file, and batched where files share
    compile arguments and configuration and batching is asked for."""
    checks_of, groups = {}, {}
    for e in chosen:
        name = source_of(e)
        config = config_of(name)
        if config not in checks_of:
            checks_of[config] = enabled_checks(build_dir, name)
        # A batch's unit is in unit_dir, and clang-tidy reads the main file's configuration:
        # only files whose configuration is the one found there are batched.
        together = batch > 1 and config == configs_above(os.path.realpath(unit_dir))
        group = (config, e["directory"], "\0".join(arguments_without_source(e))) if together else (config, name)
        groups.setdefault(group, []).append(e)
    runs, database = [], []
    for group, members in groups.items():
        checks, header_filter = checks_of[group[0]]
        parts = [members[i:i + batch] for i in range(0, len(members), max(1, batch))]
        for part in parts:
            if len(part) == 1:
                runs.append(Run(part, checks))
                continue
            whole = [c for c in checks if whole_unit(c)]
            runs.extend(Run([e], whole) for e in part if whole)
            names = [source_of(e) for e in part]
            unit = os.path.join(unit_dir, "batch-%s.cpp" % hashlib.sha256("\0".join(names).encode()).hexdigest()[:16])
            with open(unit, "w", encoding="utf-8") as f:
                f.write("// generated by scripts/lint_tidy.py: files checked as one unit\n")
                f.writelines('#include "%s"\n' % n for n in names)
            own = "|".join("^" + re.escape(n) + "$" for n in names)
            runs.append(Run(part, [c for c in checks if not whole_unit(c)],
                            "(%s)|%s" % (header_filter, own) if header_filter else own, unit))
            database.append({"directory": group[1], "file": unit,
                             "arguments": arguments_without_source(part[0]) + ["-o", unit + ".o", unit]})
    return runs, database


def lint_one(run, build_dir, unit_dir, keys, root, salt, cache):
    """(status, output, from the cache) of one run; a batch that does not compile is run file by file."""
    key = run.key(keys, salt, root) if cache else None
    path = os.path.join(cache, key[:2], key) if key else None
    if path and os.path.exists(path):
        with open(path, encoding="utf-8") as f:
            stored = json.load(f)
        return stored["status"], stored["output"].replace(ROOT_MARK, root), True
    status, output = run_tidy(build_dir, unit_dir, run)
    if run.unit and "[clang-diagnostic-error]" in output:
        status, output = 0, ""
        for e in run.entries:
            s, o = run_tidy(build_dir, unit_dir, Run([e], run.checks))
            status, output = max(status, s), output + o
    if path:
        os.makedirs(os.path.dirname(path), exist_ok=True)
        temporary = path + ".%d" % os.getpid()
        with open(temporary, "w", encoding="utf-8") as f:
            json.dump({"status": status, "output": output.replace(root, ROOT_MARK)}, f)
        os.replace(temporary, path)
    return status, output, False


def main():
    default_cache = os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "canhil",
                                 "clang-tidy")
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[1], usage=__doc__.split("\n")[0])
    p.add_argument("-p", dest="build_dir", required=True)
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--batch", type=int, default=32)
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
        name = source_of(e)
        if pattern.search(name) and name not in seen:
            seen.add(name)
            chosen.append(e)
    if not chosen:
        print("lint_tidy: no file of %s matches %s" % (database, o.regex), file=sys.stderr)
        return 2
    # The batches' units and their compile database, beside the build's.
    unit_dir = os.path.join(os.path.realpath(o.build_dir), "tidy-batches")
    os.makedirs(unit_dir, exist_ok=True)
    for stale in os.listdir(unit_dir):
        if stale.startswith("batch-"):
            os.remove(os.path.join(unit_dir, stale))
    try:
        runs, unit_database = plan(chosen, o.build_dir, o.batch, unit_dir)
    except RuntimeError as e:
        print("lint_tidy: %s" % e, file=sys.stderr)
        return 2
    with open(os.path.join(unit_dir, "compile_commands.json"), "w", encoding="utf-8") as f:
        json.dump(unit_database, f, indent=1)
    salt = tidy_version()
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, o.jobs)) as pool:
        keys = dict(zip((source_of(e) for e in chosen),
                        pool.map(lambda e: text_key(e, root), chosen))) if o.cache else {}
        # The longest runs first, so that no long one is left for the end with the
        # other worker idle: the batches, then the files by size (the static
        # analyser's time grows with the file's own code).
        ordered = sorted(runs, key=lambda r: (r.unit is None, -sum(os.path.getsize(source_of(e)) for e in r.entries)))
        results = pool.map(lambda r: lint_one(r, o.build_dir, unit_dir, keys, root, salt, o.cache),
                           ordered)
        failed, reused = 0, 0
        for status, output, cached in results:
            reused += cached
            if status != 0:
                failed += 1
                sys.stdout.write(output if output.endswith("\n") or not output else output + "\n")
    batches = sum(1 for r in runs if r.unit)
    print("lint_tidy: %d file(s), %d run(s) (%d file by file, %d of batched files), %d from the cache, %d with findings"
          % (len(chosen), len(runs), len(runs) - batches, batches, reused, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
