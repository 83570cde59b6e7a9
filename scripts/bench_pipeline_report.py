#!/usr/bin/env python3
"""The table of scripts/bench_pipeline.sh from its run folders (OUT/BUILD.SET.MODE.RUN/).

usage: bench_pipeline_report.py OUT RUNS "BUILDS" "MODES" "SETS"
Medians over the runs; the last line printed is JSON with every number.
"""
import json
import os
import statistics
import sys

# Stages shown as columns, in pipeline order (others in stats.json are in the JSON only).
STAGES = ["image_load", "tracking", "pose", "reuse", "ba", "map", "mesh", "tsdf"]


def camera_interval(trajectory):
    """Median step between the processed frames' stamps [s] (0 when fewer than two)."""
    stamps = []
    with open(trajectory) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                stamps.append(float(line.split()[0]))
    steps = [b - a for a, b in zip(stamps, stamps[1:]) if b > a]
    return statistics.median(steps) if steps else 0.0


def one_run(prefix):
    stats = json.load(open(os.path.join(prefix, "stats.json")))
    # "[MINOR_FAULTS] USER SYS ELAPSED" (/usr/bin/time; older runs have no fault count)
    fields = open(prefix + ".time").read().split()
    user, sys_, elapsed = map(float, fields[-3:])
    faults = float(fields[-4]) if len(fields) >= 4 else float("nan")
    frames = stats["frames"]
    fps = frames / stats["wall_time_s"] if stats["wall_time_s"] > 0 else 0.0
    dt = camera_interval(os.path.join(prefix, "trajectory.txt"))
    run = {
        "frames": frames,
        "tracked": stats["tracked_frames"],
        "init_retries": stats["init_retries"],
        "relocalizations": stats["relocalizations"],
        "fps": fps,
        "rt": fps * dt,
        "cpu_ms_per_frame": 1000.0 * (user + sys_) / max(frames, 1),
        "sys_ms_per_frame": 1000.0 * sys_ / max(frames, 1),
        "faults_per_frame": faults / max(frames, 1),
        "process_s": elapsed,
        "stage_ms": {k: v["mean"] for k, v in stats.get("timing_ms", {}).items()},
        "cpu_ms": dict(stats.get("cpu_ms", {})),
    }
    dense = stats.get("dense")
    if dense:
        run["dense"] = dense
    # vitamin_e_evaluate's JSON line, when the clip has a ground truth
    if os.path.exists(prefix + ".ate.json"):
        try:
            run["ate_cm"] = 100.0 * json.load(open(prefix + ".ate.json"))["ate_rmse_m"]
        except (ValueError, KeyError):
            pass
    return run


def median_of(runs, key):
    return statistics.median(r[key] for r in runs)


def median_map(runs, key):
    keys = sorted({k for r in runs for k in r[key]})
    return {k: statistics.median(r[key][k] for r in runs if k in r[key]) for k in keys}


def main():
    if len(sys.argv) != 6 or not sys.argv[2].isdigit():
        if any(a in ("-h", "--help") for a in sys.argv[1:]):
            sys.stdout.write(__doc__)
            return
        sys.exit(__doc__)
    out, nruns, builds, modes, sets = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4].split(), sys.argv[5].split()
    result = {"runs": nruns, "load": open("/proc/loadavg").read().split()[:3], "cores": os.cpu_count(), "sets": {}}
    lines = []
    for s in sets:
        result["sets"][s] = {}
        lines.append(f"== {s} ==")
        head = f"{'build':6} {'mode':10} {'fps':>6} {'rt':>5} {'cpu/f':>6} {'sys/f':>5} {'flt/f':>6} {'eff':>5} |" + "".join(
            f" {st[:8]:>8}" for st in STAGES) + " | tracked reinit reloc | ATE cm"
        lines.append(head)
        for b in builds:
            per_mode = {}
            for m in modes:
                runs = [one_run(os.path.join(out, f"{b}.{s}.{m}.{i}")) for i in range(1, nruns + 1)]
                agg = {k: median_of(runs, k) for k in ("fps", "rt", "cpu_ms_per_frame", "sys_ms_per_frame", "faults_per_frame",
                                                  "process_s")}
                agg["stage_ms"] = median_map(runs, "stage_ms")
                agg["cpu_ms"] = median_map(runs, "cpu_ms")
                agg["frames"] = runs[0]["frames"]
                agg["tracked"] = [r["tracked"] for r in runs]
                agg["init_retries"] = [r["init_retries"] for r in runs]
                agg["relocalizations"] = [r["relocalizations"] for r in runs]
                agg["fps_runs"] = [r["fps"] for r in runs]
                if "dense" in runs[0]:
                    agg["dense"] = [r.get("dense") for r in runs]
                if all("ate_cm" in r for r in runs):
                    agg["ate_cm"] = median_of(runs, "ate_cm")
                    agg["ate_cm_runs"] = [r["ate_cm"] for r in runs]
                per_mode[m] = agg
            if "sequential" in per_mode and "pipelined" in per_mode and per_mode["sequential"]["fps"] > 0:
                per_mode["pipelined"]["efficiency"] = per_mode["pipelined"]["fps"] / per_mode["sequential"]["fps"]
            for m, a in per_mode.items():
                eff = f"{a['efficiency']:5.2f}" if "efficiency" in a else "    -"
                cells = "".join(f" {a['stage_ms'][st]:8.2f}" if st in a["stage_ms"] else f" {'-':>8}" for st in STAGES)
                lines.append(f"{b:6} {m:10} {a['fps']:6.1f} {a['rt']:5.2f} {a['cpu_ms_per_frame']:6.1f}"
                             f" {a['sys_ms_per_frame']:5.1f} {a['faults_per_frame']:6.0f} {eff} |{cells}"
                             f" | {'/'.join(map(str, a['tracked']))} of {a['frames']}"
                             f" {'/'.join(map(str, a['init_retries']))} {'/'.join(map(str, a['relocalizations']))}"
                             f" | {'/'.join(f'{x:.2f}' for x in a['ate_cm_runs']) if 'ate_cm' in a else '-'}")
                if a["cpu_ms"]:
                    cpu = ", ".join(f"{k} {v:.2f}" for k, v in a["cpu_ms"].items())
                    # The stages' CPU over the runner's wall time: how many cores the pipeline kept busy
                    # (the tracker's stripe threads and the start-up are left out).
                    busy = sum(a["cpu_ms"].values()) * a["fps"] / 1000.0
                    lines.append(f"{'':6} {'':10} CPU ms/frame by thread stage: {cpu}; cores busy (their sum x fps) {busy:.2f}")
            result["sets"][s][b] = per_mode
        if "base" in builds:
            for m in modes:
                n, o = result["sets"][s]["new"][m]["fps"], result["sets"][s]["base"][m]["fps"]
                lines.append(f"new/base fps, {m}: {n / o:.2f}" if o > 0 else f"new/base fps, {m}: -")
    print("\n".join(lines))
    print("(fps: frames / runner wall time; rt: real-time factor at the camera's rate; cpu/f: process CPU ms per"
          " frame, all threads; sys/f: of it in the kernel; flt/f: minor page faults per frame; eff: pipelined /"
          " sequential fps; stage columns: mean wall ms per frame; ATE cm: each run's Sim(3) RMSE, when the clip has a"
          " ground truth)")
    print(json.dumps(result))


if __name__ == "__main__":
    main()
