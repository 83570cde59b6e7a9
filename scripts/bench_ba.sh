#!/usr/bin/env bash
# Subspace Gauss-Newton BA vs Ceres (LM, SPARSE_SCHUR and DENSE_SCHUR) on synthetic problems
# (1 px noise, 5% outliers, Geman-McClure sigma 2 px, relative cost tolerance 1e-6 for both):
# batch 10 cameras x {1k,5k,20k,50k} points from a perturbed start, and incremental
# per-frame re-optimization in a sliding 10-camera window holding ~{5k,20k} points.
#   ./scripts/bench_ba.sh [--quick] [--no-ceres] [--threads N] [--threads2 M] [--free-cams K] [--frames F] [--point-iterations P]
#                         [--point-extrapolation E] [--point-tolerance T]
# --help lists the options. Last line of the output: JSON summary. Wall-clock ms (and process
# CPU ms, which stays meaningful on a loaded machine) per solve; for incremental rows, means per frame.
# incremental_ms_per_frame is the 5k-point window solved to the tolerance (not the 5-sweep cap).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bin="$(ve_bench_bin bench_optimization_ba)"
exec "$bin" "$@" 2> >(grep -v -e '^WARNING: Logging before' >&2)
