#!/usr/bin/python3
"""clang-tidy on every translation unit of the build (src, test, bench) and, through them, the
project's headers, with a result cache. Run through ./scripts/tidy.sh (it picks the clang-tidy).

A unit's result is kept under ${XDG_CACHE_HOME:-~/.cache}/vitamin_e/tidy/, keyed by the
clang-tidy version, every .clang-tidy of the tree, the header filter, the unit's compile command
and its preprocessed text with comments (so a NOLINT counts); the checkout's and workspace's
paths are left out of the key, so a fresh clone at the same commit reuses it. A result not used
for 30 days is deleted. The preprocessing
is g++'s (the build's compiler): a change that only clang's branches of a system header would
see is missed; --no-cache checks everything again.
"""
import argparse
import concurrent.futures
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys
import time

HEADER_FILTER = ".*/vitamin_e/(include|src|test|bench)/.*"
CACHE_DAYS = 30
FINDING = re.compile(r"(warning|error): ")


def fail(msg):
    print("error: " + msg, file=sys.stderr)
    sys.exit(2)


class Paths:
    """The checkout and workspace paths, replaced by tokens in keys and in what is printed."""

    def __init__(self, root, ws):
        self.subs = [(os.path.join(ws, "src", "vitamin_e") + "/", ""), (ws, "@WS@"), (root + "/", ""), (root, "@ROOT@")]

    def strip(self, text):
        for a, b in self.subs:
            text = text.replace(a, b)
        return text


def preprocess_command(entry):
    """The unit's compile command with -E -C instead of compiling to an object."""
    args = entry["arguments"] if "arguments" in entry else shlex.split(entry["command"])
    out, skip = [], False
    for a in args:
        if skip:
            skip = False
            continue
        if a == "-o":
            skip = True
            continue
        if a == "-c":
            continue
        out.append(a)
    return out + ["-E", "-C", "-o", "-"]


def check_unit(entry, tidy, db_dir, common_key, paths, cache_dir, read_cache):
    """Returns (findings, from_cache); findings are lines, paths relative to the checkout."""
    src = entry["file"]
    key = None
    pre = subprocess.run(preprocess_command(entry), cwd=entry["directory"], capture_output=True)
    if pre.returncode == 0:
        h = hashlib.sha256(common_key)
        h.update(paths.strip(entry.get("command", " ".join(entry.get("arguments", [])))).encode())
        h.update(paths.strip(pre.stdout.decode(errors="replace")).encode())
        key = h.hexdigest()
        cached = os.path.join(cache_dir, key[:2], key)
        if read_cache and os.path.isfile(cached):
            os.utime(cached)  # used: kept by the pruning in main()
            with open(cached) as f:
                return f.read().splitlines(), True
    run = subprocess.run([tidy, "-p", db_dir, "--quiet", "--header-filter=" + HEADER_FILTER, src],
                         capture_output=True, text=True)
    text = paths.strip(re.sub(r"\x1b\[[0-9;]*m", "", run.stdout + run.stderr))
    findings = sorted({line for line in text.splitlines() if FINDING.search(line)})
    if run.returncode != 0 and not findings:
        fail("clang-tidy failed on %s without a diagnostic:\n%s" % (paths.strip(src), text[-2000:]))
    # A unit that does not compile (an error of clang's) is not kept: it is checked again.
    if key and not any("clang-diagnostic-error" in f for f in findings):
        path = os.path.join(cache_dir, key[:2], key)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        tmp = "%s.%d.tmp" % (path, os.getpid())
        with open(tmp, "w") as f:
            f.write("".join(line + "\n" for line in findings))
        os.replace(tmp, path)
    return findings, False


def main():
    ap = argparse.ArgumentParser(prog="tidy.sh", description=__doc__.split("\n\n")[0])
    ap.add_argument("--clang-tidy", required=True, help=argparse.SUPPRESS)
    ap.add_argument("-j", type=int, default=os.cpu_count(), help="parallel clang-tidy processes (default: nproc)")
    ap.add_argument("--no-cache", action="store_true", help="check every unit again (the cache is still written)")
    ap.add_argument("regex", nargs="?", default=".*", help="only the units whose path matches (e.g. 'src/pipeline/')")
    a = ap.parse_args()
    if a.j < 1:
        fail("tidy.sh: -j needs a number >= 1")
    root, ws = os.environ["VE_ROOT"], os.environ["VE_WS"]
    db_dir = os.path.join(ws, "build")
    db_file = os.path.join(db_dir, "compile_commands.json")
    if not os.path.isfile(db_file):
        fail("no %s: build first (./scripts/build.sh), then run tidy.sh again" % db_file)
    try:
        units = [e for e in json.load(open(db_file)) if re.search(a.regex, e["file"])]
    except re.error as e:
        fail("tidy.sh: bad REGEX '%s': %s" % (a.regex, e))
    if not units:
        fail("tidy.sh: no unit of %s matches '%s'" % (db_file, a.regex))
    paths = Paths(root, ws)

    version = subprocess.run([a.clang_tidy, "--version"], capture_output=True, text=True).stdout
    configs = subprocess.run(["git", "-C", root, "ls-files", "-co", "--exclude-standard", "*.clang-tidy"],
                             capture_output=True, text=True).stdout.split()
    common = hashlib.sha256(version.encode() + HEADER_FILTER.encode())
    for c in sorted(configs):
        with open(os.path.join(root, c), "rb") as f:
            common.update(c.encode() + b"\0" + f.read())
    cache_root = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    cache_dir = os.path.join(cache_root, "vitamin_e", "tidy")

    start = time.monotonic()
    findings, hits = set(), 0
    with concurrent.futures.ThreadPoolExecutor(a.j) as pool:
        jobs = [pool.submit(check_unit, e, a.clang_tidy, db_dir, common.digest(), paths, cache_dir, not a.no_cache)
                for e in units]
        for job in concurrent.futures.as_completed(jobs):
            unit_findings, cached = job.result()
            hits += cached
            findings.update(unit_findings)
    took = time.monotonic() - start
    # Results unused for CACHE_DAYS go: a header change leaves one stale entry per unit.
    cutoff = time.time() - CACHE_DAYS * 86400
    for d, _, names in os.walk(cache_dir):
        for name in names:
            path = os.path.join(d, name)
            if os.path.getmtime(path) < cutoff:
                os.remove(path)
    summary = "%d unit(s) checked, %d from the cache, %.0f s" % (len(units), hits, took)
    if findings:
        print("\n".join(sorted(findings)))
        print("tidy: %d finding(s); %s" % (len(findings), summary))
        sys.exit(1)
    print("tidy: OK (%s)" % summary)


if __name__ == "__main__":
    main()
