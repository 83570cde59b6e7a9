#!/usr/bin/env bash
# The whole offline pipeline (SLAM, per-frame mesh, TSDF: vitamin_e_run with dense on) timed on a
# render and a KITTI clip, sequential and --pipelined, for this build and (with --base) another one
# side by side: runs alternate (B A B A ...) so that both builds see the same machine load.
#   ./scripts/bench_pipeline.sh [--base DIR] [--runs N] [--frames N] [--stride N] [--out DIR]
#                               [--render PATH] [--kitti PATH] [--only render|kitti] [--modes "sequential pipelined"]
# DIR: a folder holding another build's vitamin_e_run (e.g. the previous commit's
#   .ws/devel/lib/vitamin_e; docs/PERFORMANCE.md shows how to build one beside this checkout).
# Defaults: V1_01_easy_30s under VE_RENDERS (../renders) with config/euroc.yaml, KITTI 07 frames
# 0-159 under VE_SHARED (../shared) with config/kitti.yaml; 2 runs; all frames.
# --config-dir DIR: euroc.yaml and kitti.yaml from DIR for both builds (an older build that lacks
#   today's defaults runs the configs of its own commit: `git show REV:config/euroc.yaml > DIR/euroc.yaml`).
# --base-config-dir DIR: the --base build's euroc.yaml and kitti.yaml instead (a change of the configs
#   or of a default is then timed against the configs it replaces, with the same binary as --base).
# Per build, dataset and mode (medians over the runs):
#   fps        processed frames / the runner's wall time for them (stats.json wall_time_s)
#   rt         real-time factor: fps x the camera's frame interval (median of the trajectory's steps)
#   cpu/f      process CPU (user + sys, every thread) per frame [ms]: what the frame costs the machine
#   sys/f      of it, the kernel's [ms] (page faults, most of it: docs/PERFORMANCE.md, Page faults)
#   flt/f      minor page faults per frame (/usr/bin/time %R)
#   stages     mean wall ms per frame of each stage (stats.json timing_ms); in --pipelined mode they
#              overlap; stats.json cpu_ms (builds that have it) gives the CPU ms per frame of each
#              thread's stage (a stage's helper threads, e.g. the tracker's stripes, count in cpu/f only)
#              and the cores those stages kept busy (their sum x fps)
#   eff        parallel efficiency: pipelined fps / sequential fps of the same build
#   ATE        trajectory error [cm] (vitamin_e_evaluate, Sim(3) RMSE) against the clip's ground truth
#              (groundtruth_cam0_tum.txt or poses.txt in it), when there is one, run by run: a
#              --pipelined run gives the same trajectory every time (a build before 7538326 did not)
# Last line: JSON with every number. Timing only: accuracy is scripts/evaluate_suite.sh's.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
usage="usage: ./scripts/bench_pipeline.sh [--base DIR] [--runs N] [--frames N] [--stride N] [--out DIR] [--render PATH] [--kitti PATH] [--only render|kitti] [--modes LIST] [--config-dir DIR] [--base-config-dir DIR]"
ve_help_on_request "$@"

base="" runs=2 frames=0 stride=1 only="" modes="sequential pipelined" config_dir="$VE_ROOT/config" base_config_dir=""
out="$(mktemp -d /tmp/ve_bench_pipeline.XXXXXX)"
render="$(ve_list_path ../renders/V1_01_easy_30s)"
kitti="$(ve_list_path ../shared/data/kitti/07_first160)"
while [ $# -gt 0 ]; do
  case "$1" in
    --base|--runs|--frames|--stride|--out|--render|--kitti|--only|--modes|--config-dir|--base-config-dir)
      [ $# -ge 2 ] || ve_die "$1 needs a value ($usage)" ;;&
    --base) base="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --stride) stride="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --render) render="$2"; shift 2 ;;
    --kitti) kitti="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    --modes) modes="$2"; shift 2 ;;
    --config-dir) config_dir="$2"; shift 2 ;;
    --base-config-dir) base_config_dir="$2"; shift 2 ;;
    *) ve_die "unknown option '$1' ($usage)" ;;
  esac
done
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || ve_die "--runs must be a positive integer, got '$runs'"
[[ "$frames" =~ ^[0-9]+$ ]] || ve_die "--frames must be a non-negative integer, got '$frames'"
[[ "$stride" =~ ^[1-9][0-9]*$ ]] || ve_die "--stride must be a positive integer, got '$stride'"
[ -n "$base_config_dir" ] || base_config_dir="$config_dir"
for c in euroc kitti; do
  [ -f "$config_dir/$c.yaml" ] || ve_die "--config-dir: $config_dir/$c.yaml is missing"
  [ -f "$base_config_dir/$c.yaml" ] || ve_die "--base-config-dir: $base_config_dir/$c.yaml is missing"
done
case "$only" in ""|render|kitti) ;; *) ve_die "--only takes render or kitti, got '$only'" ;; esac
for m in $modes; do
  case "$m" in sequential|pipelined) ;; *) ve_die "--modes: unknown mode '$m' (sequential, pipelined)" ;; esac
done

new="$VE_WS/devel/lib/vitamin_e"
if [ "${VE_NO_BUILD:-0}" != 1 ]; then "$VE_ROOT/scripts/build.sh" --target vitamin_e_run >&2; fi
[ -x "$new/vitamin_e_run" ] || ve_die "$new/vitamin_e_run is missing: build first"
builds=(new)
declare -A bin=([new]="$new")
declare -A configs=([new]="$config_dir" [base]="$base_config_dir")
if [ -n "$base" ]; then
  [ -x "$base/vitamin_e_run" ] || ve_die "--base: $base/vitamin_e_run is missing"
  builds=(new base)
  bin[base]="$base"
fi

sets=()
if [ "$only" != kitti ]; then
  [ -d "$render" ] || ve_die "render '$render' does not exist (--render PATH, or --only kitti)"
  sets+=("render|$render|euroc.yaml")
fi
if [ "$only" != render ]; then
  [ -d "$kitti" ] || ve_die "KITTI clip '$kitti' does not exist (--kitti PATH, or --only render)"
  sets+=("kitti|$kitti|kitti.yaml")
fi
mkdir -p "$out"
extra=(--stride "$stride")
[ "$frames" -gt 0 ] && extra+=(--max-frames "$frames")

ve_info "machine: $(nproc) cores, $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)"
ve_info "load before: $(cut -d' ' -f1-3 /proc/loadavg); runs in $out"
for ((i = 1; i <= runs; ++i)); do
  for s in "${sets[@]}"; do
    IFS='|' read -r name path config <<<"$s"
    gt=""
    for f in groundtruth_cam0_tum.txt poses.txt; do
      if [ -f "$path/$f" ]; then gt="$path/$f"; break; fi
    done
    for mode in $modes; do
      flag=()
      [ "$mode" = pipelined ] && flag=(--pipelined)
      # Alternate which build goes first from run to run.
      order=("${builds[@]}")
      if ((i % 2 == 0)) && [ ${#builds[@]} = 2 ]; then order=("${builds[1]}" "${builds[0]}"); fi
      for b in "${order[@]}"; do
        dir="$out/$b.$name.$mode.$i"
        /usr/bin/time -f "%R %U %S %e" -o "$dir.time" "${bin[$b]}/vitamin_e_run" --dataset "$path" --config "${configs[$b]}/$config" \
          --out "$dir" --quiet "${flag[@]}" "${extra[@]}" >/dev/null 2>"$dir.stderr" \
          || { cat "$dir.stderr" >&2; ve_die "run $dir failed"; }
        if [ -n "$gt" ] && [ -x "$new/vitamin_e_evaluate" ]; then
          "$new/vitamin_e_evaluate" "$dir/trajectory.txt" "$gt" 2>/dev/null | tail -n 1 >"$dir.ate.json" || rm -f "$dir.ate.json"
        fi
        ve_info "$b $name $mode run $i: $(python3 -c "import json,sys; s=json.load(open(sys.argv[1])); print('%d frames in %.1f s' % (s['frames'], s['wall_time_s']))" "$dir/stats.json") (load $(cut -d' ' -f1 /proc/loadavg))"
      done
    done
  done
done
ve_info "load after: $(cut -d' ' -f1-3 /proc/loadavg)"

/usr/bin/python3 "$VE_ROOT/scripts/bench_pipeline_report.py" "$out" "$runs" "${builds[*]}" "$modes" \
  "$(for s in "${sets[@]}"; do printf '%s ' "${s%%|*}"; done)"
