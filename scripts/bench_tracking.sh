#!/usr/bin/env bash
# Dense curvature-extrema tracker vs OpenCV KLT on a render of
# tools/render_sequence.py (exact ground truth from scene.json + poses).
#   ./scripts/bench_tracking.sh RENDER_DIR [--frames N] [other bench_tracking_render options]
# e.g. ./scripts/bench_tracking.sh /work/renders/V1_01_easy_30s --frames 300
# --help lists the options. Last line of the output: JSON summary. Timings are
# wall clock; "CPU ms" is process CPU time, which stays meaningful on a loaded machine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if ve_wants_help "$@"; then bin="$(ve_bench_bin bench_tracking_render)"; exec "$bin" --help; fi
[ $# -ge 1 ] || ve_die "usage: bench_tracking.sh RENDER_DIR [options] (see --help)"
dataset="$1"; shift
case "$dataset" in -*) ve_die "the first argument must be RENDER_DIR, got '$dataset' (see --help)" ;; esac
[ -f "$dataset/scene.json" ] || ve_die "$dataset: not a render (no scene.json)"
bin="$(ve_bench_bin bench_tracking_render)"
exec "$bin" "$dataset" "$@"
