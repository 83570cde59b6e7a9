#!/usr/bin/env bash
# Dense reconstruction benchmark on a render of render_sequence.py, measured
# against its exact surfaces (scene.json). Default input: the SLAM itself
# (pipeline::System with config/euroc.yaml, as vitamin_e_run) on every frame;
# its per-frame points and poses are meshed (Delaunay + NLTGV2-L1), fused in
# TSDFs of 15 cm and 2.5 cm voxels (converted to map units by the Sim(3)
# alignment of the trajectory to ground truth), and the meshes are mapped by
# that Sim(3) before they are measured. --gt-input: ground-truth poses and
# ray-cast noisy depth instead.
#   ./scripts/bench_dense.sh RENDER_DIR [--config YAML] [--gt-input] [bench_fusion_dense options]
# Builds bench_fusion_dense in $VE_WS (default .ws/) and runs it; the last line
# of the output is a JSON summary. Meshes (ground-truth frame, metres) are
# written to $VE_BENCH_OUT if set.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if ve_wants_help "$@"; then bin="$(ve_bench_bin bench_fusion_dense)"; exec "$bin" --help; fi
[ $# -ge 1 ] || ve_die "usage: bench_dense.sh RENDER_DIR [--config YAML] [--gt-input] [options] (see --help)"
render="$1"; shift
case "$render" in -*) ve_die "the first argument must be RENDER_DIR, got '$render' (see --help)" ;; esac
[ -f "$render/scene.json" ] || ve_die "$render/scene.json not found (not a render_sequence.py output?)"
[ -f "$render/groundtruth_cam0_tum.txt" ] || ve_die "$render/groundtruth_cam0_tum.txt not found"
bin="$(ve_bench_bin bench_fusion_dense)"
extra=()
if [ -n "${VE_BENCH_OUT:-}" ]; then mkdir -p "$VE_BENCH_OUT"; extra+=(--out "$VE_BENCH_OUT"); fi
case " $* " in
  *" --config "*|*" --gt-input "*) ;;
  *) extra+=(--config "$VE_ROOT/config/euroc.yaml") ;;
esac
exec "$bin" "$render" "${extra[@]}" "$@"
