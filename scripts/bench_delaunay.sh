#!/usr/bin/env bash
# Timing of the 2D Delaunay triangulation of a frame's points (meshing::delaunayTriangulate):
# uniformly random points in a 752x480 image, median and p95 over repeated runs.
#   ./scripts/bench_delaunay.sh [--points N] [--repeats R] [--seed S]
# Last line of the output: JSON summary.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"
bin="$(ve_bench_bin bench_meshing_delaunay)"
exec "$bin" "$@"
