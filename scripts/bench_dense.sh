#!/usr/bin/env bash
# Dense reconstruction benchmark (Delaunay meshing + NLTGV2-L1 + TSDF at 15 cm and
# 2.5 cm) on a render of render_sequence.py, with ground-truth surfaces.
#   ./scripts/bench_dense.sh RENDER_DIR [--trajectory TRAJ] [bench_fusion_dense options]
# Builds bench_fusion_dense in $VE_WS (default .ws/) and runs it; the last line
# of the output is a JSON summary. Meshes are written to $VE_BENCH_OUT if set.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
[ $# -ge 1 ] || ve_die "usage: bench_dense.sh RENDER_DIR [--trajectory TRAJ] [options]"
render="$1"; shift
[ -f "$render/scene.json" ] || ve_die "$render/scene.json not found (not a render_sequence.py output?)"
[ -f "$render/groundtruth_cam0_tum.txt" ] || ve_die "$render/groundtruth_cam0_tum.txt not found"
"$VE_ROOT/scripts/build.sh" --target bench_fusion_dense >&2
extra=()
if [ -n "${VE_BENCH_OUT:-}" ]; then mkdir -p "$VE_BENCH_OUT"; extra+=(--out "$VE_BENCH_OUT"); fi
exec "$VE_WS/devel/lib/vitamin_e/bench_fusion_dense" "$render" "${extra[@]}" "$@"
