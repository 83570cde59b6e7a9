#!/usr/bin/python3
"""Plots an evaluated trajectory: top view (x-y) of the ground truth and the
aligned estimate, and the position error over time.

    plot_trajectory.py --gt GT_TUM --estimate ALIGNED_TUM --errors ERRORS --out OUT.png [--title T]

GT_TUM / ALIGNED_TUM are TUM files (t tx ty tz qx qy qz qw); ERRORS has lines
't error_m' (vitamin_e_evaluate --gt-out/--aligned-out/--errors-out write them).
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path, cols):
    rows = []
    with open(path) as fh:
        for line in fh:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            vals = [float(v) for v in line.split()]
            if len(vals) != cols:
                sys.exit("error: %s: expected %d numbers per line, got %d" % (path, cols, len(vals)))
            rows.append(vals)
    return np.array(rows, dtype=float).reshape(-1, cols)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt", required=True)
    ap.add_argument("--estimate", required=True)
    ap.add_argument("--errors", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    gt = load(args.gt, 8)
    est = load(args.estimate, 8)
    err = load(args.errors, 2)
    if len(gt) == 0 or len(est) == 0:
        sys.exit("error: nothing to plot (empty ground truth or estimate)")

    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(13, 5.5), gridspec_kw=dict(width_ratios=[1.1, 1.0]))
    # Ground truth over the estimate's time span only (ground truth may be longer).
    t0, t1 = est[0, 0] - 0.5, est[-1, 0] + 0.5
    sel = (gt[:, 0] >= t0) & (gt[:, 0] <= t1)
    g = gt[sel] if sel.sum() >= 2 else gt
    ax0.plot(g[:, 1], g[:, 2], "-", color="0.35", lw=2.0, label="ground truth")
    ax0.plot(est[:, 1], est[:, 2], "-", color="tab:red", lw=1.0, label="estimate (aligned)")
    ax0.plot(g[0, 1], g[0, 2], "o", color="0.35", ms=6, label="start")
    ax0.set_xlabel("x [m]")
    ax0.set_ylabel("y [m]")
    ax0.set_aspect("equal", adjustable="datalim")
    ax0.grid(True, alpha=0.3)
    ax0.legend(loc="best", fontsize=9)
    ax0.set_title("top view (x-y)")

    if len(err):
        ts = err[:, 0] - est[0, 0]
        ax1.plot(ts, 100.0 * err[:, 1], "-", color="tab:blue", lw=1.0)
        rmse = np.sqrt(np.mean(err[:, 1] ** 2))
        ax1.axhline(100.0 * rmse, color="tab:orange", ls="--", lw=1.0, label="RMSE %.2f cm" % (100.0 * rmse))
        ax1.legend(loc="best", fontsize=9)
    ax1.set_xlabel("time since first estimate [s]")
    ax1.set_ylabel("position error [cm]")
    ax1.set_ylim(bottom=0.0)
    ax1.grid(True, alpha=0.3)
    ax1.set_title("position error after alignment")
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print("plot written to %s" % args.out)


if __name__ == "__main__":
    main()
