#!/usr/bin/python3
"""Runs vitamin_e on a set of clips under several configurations and prints
one table: a row per clip, a column per configuration (Sim(3) ATE RMSE).

  ./scripts/config_sweep.py CLIPS --variant NAME[:section.key=value,...] [--variant ...]
                            [--out DIR] [--bin DIR] [--dense]

CLIPS: one clip per line, `NAME CONFIG DATASET [GROUNDTRUTH|-] [vitamin_e_run flags...]`
('#' comments; relative paths from the repository's root; `../shared` and
`../renders` follow VE_SHARED and VE_RENDERS as in the suite lists). GROUNDTRUTH
'-' or missing: the dataset's own (groundtruth_cam0_tum.txt, poses.txt).
Extra flags go to vitamin_e_run, e.g. `--start-frame 50`.

A variant is the clip's own CONFIG with the listed keys changed ("NAME" alone:
unchanged). The first variant is the reference: the last rows give, per
variant, the geometric mean of the ATE ratio to it and the worst clip. A cell is
the ATE in cm; '!N%' marks a run that tracked only N % of the frames after its
initialization, 'iN' one that started N new maps, 'rN' one that relocalized N
times, 'x' one that failed. Dense reconstruction
is off unless --dense (it does not change the trajectory, only the time).
--keep reuses an earlier run of the same clip and config in DIR (same binaries:
the caller's promise). Outputs: DIR/<variant>/<clip>/ (trajectory, stats,
result.json), DIR/table.md, DIR/results.json.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def list_path(p):
    """A path of a list file: relative to the repository, with ../shared and
    ../renders redirected by VE_SHARED and VE_RENDERS."""
    if not p or p == "-":
        return ""
    for prefix, env in (("../shared", "VE_SHARED"), ("../renders", "VE_RENDERS")):
        if (p == prefix or p.startswith(prefix + "/")) and os.environ.get(env):
            p = os.environ[env] + p[len(prefix):]
            break
    return p if os.path.isabs(p) else os.path.normpath(os.path.join(ROOT, p))


def parse_clips(path):
    clips = []
    with open(path) as fh:
        for n, line in enumerate(fh, 1):
            words = line.split()
            if not words or words[0].startswith("#"):
                continue
            if len(words) < 3:
                sys.exit("error: %s:%d: expected NAME CONFIG DATASET [GROUNDTRUTH] [flags]" % (path, n))
            rest = words[3:]
            gt = ""
            if rest and not rest[0].startswith("--"):
                gt = "" if rest[0] == "-" else rest[0]
                rest = rest[1:]
            flags = rest
            clips.append({"name": words[0], "config": list_path(words[1]), "dataset": list_path(words[2]),
                          "groundtruth": list_path(gt), "flags": flags})
    return clips


def parse_variant(text):
    name, _, sets = text.partition(":")
    changes = []
    for item in filter(None, sets.split(",")):
        key, eq, value = item.partition("=")
        if not eq or key.count(".") != 1:
            sys.exit("error: variant '%s': '%s' is not section.key=value" % (name, item))
        changes.append((key, yaml.safe_load(value)))
    return {"name": name, "changes": changes}


def default_groundtruth(dataset):
    for f in ("groundtruth_cam0_tum.txt", "poses.txt"):
        if os.path.isfile(os.path.join(dataset, f)):
            return os.path.join(dataset, f)
    return ""


def write_config(base, changes, dense, path):
    with open(base) as fh:
        cfg = yaml.safe_load(fh) or {}
    for key, value in changes:
        section, k = key.split(".")
        cfg.setdefault(section, {})[k] = value
    if not dense:
        cfg.setdefault("dense", {})["enabled"] = False
    with open(path, "w") as fh:
        yaml.safe_dump(cfg, fh)


def run_clip(clip, variant, args, out):
    os.makedirs(out, exist_ok=True)
    cfg = os.path.join(out, "config.yaml")
    saved = os.path.join(out, "result.json")
    old_cfg = open(cfg).read() if os.path.isfile(cfg) else None
    write_config(clip["config"], variant["changes"], args.dense, cfg)
    if args.keep and os.path.isfile(saved) and old_cfg == open(cfg).read():
        with open(saved) as fh:
            return json.load(fh)
    if os.path.isfile(saved):
        os.remove(saved)
    result = run_and_evaluate(clip, args, out, cfg)
    with open(saved, "w") as fh:
        json.dump(result, fh)
    return result


def run_and_evaluate(clip, args, out, cfg):
    run = [os.path.join(args.bin, "vitamin_e_run"), "--dataset", clip["dataset"], "--out", out, "--config", cfg,
           "--quiet"] + clip["flags"]
    with open(os.path.join(out, "run.log"), "w") as log:
        rc = subprocess.call(run, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    result = {"rc": rc}
    if rc != 0:
        return result
    with open(os.path.join(out, "stats.json")) as fh:
        stats = json.load(fh)
    keys = ("frames", "success_after_init", "init_retries", "relocalizations", "wall_time_s")
    result.update({k: stats.get(k) for k in keys})
    gt = clip["groundtruth"] or default_groundtruth(clip["dataset"])
    if not gt:
        return result
    ev = subprocess.run([os.path.join(args.bin, "vitamin_e_evaluate"), os.path.join(out, "trajectory.txt"), gt,
                         "--frames", str(stats.get("frames", 0))], capture_output=True, text=True)
    if ev.returncode == 0 and ev.stdout.strip():
        e = json.loads(ev.stdout.strip().splitlines()[-1])
        result["ate_m"] = e.get("ate_rmse_m")
        result["ate_path_percent"] = e.get("ate_path_percent")
    return result


def cell(r):
    if r.get("rc") != 0 or r.get("ate_m") is None:
        return "x"
    tracked = r.get("success_after_init") or 0
    mark = "" if tracked >= 1.0 and not r.get("init_retries") else " !%.0f%%" % (100.0 * tracked)
    if r.get("init_retries"):
        mark += " i%d" % r["init_retries"]
    relocs = r.get("relocalizations") or 0
    return "%.2f%s%s" % (100.0 * r["ate_m"], mark, " r%d" % relocs if relocs else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("clips")
    ap.add_argument("--variant", action="append", required=True)
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "sweep"))
    ap.add_argument("--bin", default=os.path.join(ROOT, ".ws", "devel", "lib", "vitamin_e"))
    ap.add_argument("--dense", action="store_true")
    ap.add_argument("--keep", action="store_true",
                    help="reuse a run whose folder holds a result made with the same config (same binary assumed)")
    args = ap.parse_args()
    clips = parse_clips(args.clips)
    variants = [parse_variant(v) for v in args.variant]
    for tool in ("vitamin_e_run", "vitamin_e_evaluate"):
        if not os.access(os.path.join(args.bin, tool), os.X_OK):
            sys.exit("error: no %s in %s (build first, or pass --bin)" % (tool, args.bin))
    results = {}
    for clip in clips:
        if not os.path.exists(clip["dataset"]):
            print("%s: %s does not exist: not run" % (clip["name"], clip["dataset"]), file=sys.stderr)
            continue
        for v in variants:
            r = run_clip(clip, v, args, os.path.join(args.out, v["name"], clip["name"]))
            results.setdefault(clip["name"], {})[v["name"]] = r
            print("%-24s %-24s %s" % (clip["name"], v["name"], cell(r)), file=sys.stderr, flush=True)
    names = [v["name"] for v in variants]
    lines = ["| clip (ATE, cm) | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    for clip, row in results.items():
        lines.append("| %s | %s |" % (clip, " | ".join(cell(row.get(n, {})) for n in names)))
    gm, worst = [], []
    for n in names:
        logs, w = [], (0.0, "")
        for clip, row in results.items():
            a, b = row.get(names[0], {}).get("ate_m"), row.get(n, {}).get("ate_m")
            if a and b:
                logs.append(math.log(b / a))
                w = max(w, (b / a, clip))
        gm.append("%.2f" % math.exp(sum(logs) / len(logs)) if logs else "n/a")
        worst.append("%.2f (%s)" % w if w[1] else "n/a")
    lines.append("| geometric mean ratio to %s | %s |" % (names[0], " | ".join(gm)))
    lines.append("| worst ratio | %s |" % " | ".join(worst))
    table = "\n".join(lines) + "\n"
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "table.md"), "w") as fh:
        fh.write(table)
    with open(os.path.join(args.out, "results.json"), "w") as fh:
        json.dump({"variants": [{"name": v["name"], "changes": v["changes"]} for v in variants],
                   "results": results}, fh, indent=1)
    sys.stdout.write(table)


if __name__ == "__main__":
    main()
