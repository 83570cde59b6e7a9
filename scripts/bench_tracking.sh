#!/usr/bin/env bash
# Dense curvature-extrema tracker vs OpenCV KLT on a render of
# tools/render_sequence.py (exact ground truth from scene.json + poses).
#   ./scripts/bench_tracking.sh RENDER_DIR [--frames N] [other bench_tracking_render options]
# e.g. ./scripts/bench_tracking.sh /work/renders/V1_01_easy_30s --frames 300
# Last line of the output: JSON summary. Timings are wall clock; "CPU ms" is
# process CPU time, which stays meaningful on a loaded machine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
[ $# -ge 1 ] || ve_die "usage: bench_tracking.sh RENDER_DIR [--frames N] [...]"
dataset="$1"; shift
[ -f "$dataset/scene.json" ] || ve_die "$dataset: not a render (no scene.json)"
"$VE_ROOT/scripts/build.sh" --target bench_tracking_render >&2
exec "$VE_WS/devel/lib/vitamin_e/bench_tracking_render" "$dataset" "$@"
