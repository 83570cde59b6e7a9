#!/usr/bin/python3
"""Scale along a trajectory: estimated over true distance travelled per STEP frames.

  ./scripts/step_ratio.py TRAJECTORY GROUNDTRUTH [--step N] [--normalize A:B]

TRAJECTORY: a TUM file (vitamin_e_run's trajectory.txt) or a run folder holding one.
GROUNDTRUTH: KITTI poses.txt (times.txt beside it) or a TUM file; a dataset folder
holding poses.txt (KITTI) or groundtruth_cam0_tum.txt (project renders) also works.
Poses are matched by timestamp (nearest within 0.02 s); frame i is the i-th
ground-truth pose. A monocular map has no unit, so the ratios are divided by their
median over frames A-B (--normalize; default: all frames): a ratio that changes
along the path is a change of the map's scale. Prints FRAME:RATIO per step, where
FRAME is the step's last frame.
"""
import argparse
import os
import sys

import numpy as np


def load_tum(path):
    try:
        rows = [ln.split() for ln in open(path) if ln.strip() and not ln.lstrip().startswith("#")]
        a = np.array([[float(x) for x in r[:4]] for r in rows if len(r) >= 8])
    except (OSError, ValueError) as e:
        sys.exit(f"step_ratio: {path}: {e}")
    if len(a) == 0 or len(a) != len(rows):
        sys.exit(f"step_ratio: {path}: not a TUM trajectory (t tx ty tz qx qy qz qw per line)")
    return a[:, 0], a[:, 1:4]


def load_ground_truth(path):
    if os.path.isdir(path):
        for name in ("poses.txt", "groundtruth_cam0_tum.txt"):
            if os.path.isfile(os.path.join(path, name)):
                path = os.path.join(path, name)
                break
        else:
            sys.exit(f"step_ratio: {path}: no poses.txt or groundtruth_cam0_tum.txt")
    if not os.path.isfile(path):
        sys.exit(f"step_ratio: {path}: no such ground-truth file")
    first = next((ln for ln in open(path) if ln.strip() and not ln.startswith("#")), "").split()
    if len(first) == 12:  # KITTI: 3x4 row-major per line, stamps in times.txt
        times = os.path.join(os.path.dirname(path), "times.txt")
        if not os.path.isfile(times):
            sys.exit(f"step_ratio: {path} is KITTI poses but {times} is missing")
        try:
            poses = np.loadtxt(path).reshape(-1, 3, 4)
            stamps = np.loadtxt(times).reshape(-1)
        except (OSError, ValueError) as e:
            sys.exit(f"step_ratio: {path}: {e}")
        if len(stamps) < len(poses):
            sys.exit(f"step_ratio: {len(poses)} poses but only {len(stamps)} times")
        stamps = stamps[: len(poses)]  # a clip's times.txt may list the whole sequence
        return stamps, poses[:, :, 3]
    return load_tum(path)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("trajectory")
    p.add_argument("groundtruth")
    p.add_argument("--step", type=int, default=5)
    p.add_argument("--normalize", default="", help="A:B, the frames whose median ratio is 1")
    a = p.parse_args()
    if a.step < 1:
        sys.exit("step_ratio: --step must be >= 1")
    traj = a.trajectory
    if os.path.isdir(traj):
        traj = os.path.join(traj, "trajectory.txt")
    est_t, est_p = load_tum(traj)
    gt_t, gt_p = load_ground_truth(a.groundtruth)
    # frame index of each estimated pose (nearest ground-truth stamp)
    est = {}
    for t, pos in zip(est_t, est_p):
        i = int(np.argmin(np.abs(gt_t - t)))
        if abs(gt_t[i] - t) <= 0.02:
            est[i] = pos
    steps = []
    for i in range(a.step, len(gt_t), a.step):
        if i in est and i - a.step in est:
            true = np.linalg.norm(gt_p[i] - gt_p[i - a.step])
            if true > 1e-9:
                steps.append((i, np.linalg.norm(est[i] - est[i - a.step]) / true))
    if not steps:
        sys.exit("step_ratio: no pair of matched poses STEP frames apart")
    lo, hi = 0, len(gt_t)
    if a.normalize:
        try:
            lo, hi = (int(x) for x in a.normalize.split(":"))
        except ValueError:
            sys.exit("step_ratio: --normalize wants A:B (frame numbers)")
    ref = [r for i, r in steps if lo <= i <= hi]
    if not ref:
        sys.exit(f"step_ratio: no step ends within frames {lo}-{hi}")
    scale = float(np.median(ref))
    print(" ".join(f"{i}:{r / scale:.2f}" for i, r in steps))


if __name__ == "__main__":
    main()
