#!/usr/bin/env python3
"""ci_doc_test.py DOCS_CI_MD DEB TEAM_REPO WORK — docs/ci.md's recipes as a CI
runs them: both YAML files parsed (a real YAML parser, PyYAML), their
structure checked (the JUnit report published, the artefacts kept even when
the job fails), the two recipes' shell commands the same, then run as written
in a copy of a team's repository of the shape ci.md describes, with the
package in ci/. One change: the install step unpacks the package with
dpkg-deb -x into WORK/root and puts its bin/ first on PATH instead of
apt-get installing it, so that this machine is left as it was. The job must
end with a JUnit report of passed expectations and the artefacts."""
import glob
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import yaml


def fail(what):
    print("FAIL: " + what, file=sys.stderr)
    sys.exit(1)


def main():
    doc, deb, team, work = sys.argv[1:5]
    text = open(doc, encoding="utf-8").read()
    blocks = re.findall(r"```yaml\n(.*?)```", text, re.S)
    if len(blocks) != 2:
        fail(f"{doc}: {len(blocks)} yaml blocks, not 2 (GitHub Actions, GitLab CI)")
    github, gitlab = (yaml.safe_load(b) for b in blocks)

    # GitHub Actions: one job, checkout, the shell steps, the report and the artefacts always.
    jobs = github.get("jobs") or fail("the workflow has no jobs")
    (job,) = jobs.values()
    if job.get("container") != "debian:12":
        fail("the GitHub job does not run in debian:12")
    steps = job["steps"]
    uses = [s.get("uses", "") for s in steps]
    if not any(u.startswith("actions/checkout@") for u in uses):
        fail("no checkout step")
    report = next((s for s in steps if s.get("uses", "").startswith("mikepenz/action-junit-report@")), None)
    if report is None or report["with"]["report_paths"] != "canhil-report.xml" or report.get("if") != "always()":
        fail("the JUnit report is not published always")
    upload = next((s for s in steps if s.get("uses", "").startswith("actions/upload-artifact@")), None)
    if upload is None or "canhil-artifacts/" not in upload["with"]["path"] or upload.get("if") != "always()":
        fail("the artefacts are not kept always")
    github_lines = [line for s in steps if "run" in s for line in s["run"].strip().splitlines()]

    # GitLab CI: one job, its script, the JUnit report and the artefacts when always.
    (gjob,) = gitlab.values()
    if gjob.get("image") != "debian:12":
        fail("the GitLab job does not run in debian:12")
    artifacts = gjob["artifacts"]
    if artifacts.get("when") != "always" or artifacts["reports"]["junit"] != "canhil-report.xml":
        fail("GitLab's JUnit report is not kept always")
    if "canhil-artifacts/" not in artifacts["paths"]:
        fail("GitLab keeps no canhil-artifacts/")
    if gjob["script"] != github_lines:
        fail(f"the two recipes' commands differ:\n{gjob['script']}\n{github_lines}")

    # Run them in a team's repository.
    if os.path.exists(work):
        shutil.rmtree(work)
    repo = os.path.join(work, "repo")
    shutil.copytree(team, repo)
    os.makedirs(os.path.join(repo, "ci"))
    shutil.copy(deb, os.path.join(repo, "ci"))
    root = os.path.join(work, "root")
    env = dict(os.environ)
    for line in github_lines:
        if line == "apt-get update":
            continue
        if line.startswith("apt-get install"):
            (package,) = glob.glob(os.path.join(repo, "ci", "canhil_*_amd64.deb"))
            subprocess.run(["dpkg-deb", "-x", package, root], check=True)
            env["PATH"] = os.path.join(root, "usr", "bin") + os.pathsep + env["PATH"]
            continue
        print("+ " + line, flush=True)
        done = subprocess.run(["bash", "-c", line], cwd=repo, env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
        if done.returncode != 0:
            fail(f"`{line}` exit {done.returncode}:\n{done.stdout}")
    suites = ET.parse(os.path.join(repo, "canhil-report.xml")).getroot()
    if suites.get("failures") != "0" or suites.get("errors") != "0" or int(suites.get("tests")) < 3:
        fail("the report: " + ET.tostring(suites, encoding="unicode")[:400])
    kept = glob.glob(os.path.join(repo, "canhil-artifacts", "score", "*"))
    for name in ("trace.log", "world.csv", "canhil.log", "canhil-agent1-handler.log", "canhil-agent1-agent.log"):
        if os.path.join(repo, "canhil-artifacts", "score", name) not in kept:
            fail(f"no canhil-artifacts/score/{name}: {kept}")
    print(f"ci_doc_test: both recipes parse; their {len(github_lines)} commands ran; {suites.get('tests')} passed")


main()
