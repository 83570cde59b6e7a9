#!/usr/bin/env bash
# Runs VITAMIN-E offline over a dataset (builds vitamin_e_run first if needed).
#   ./scripts/run_dataset.sh DATASET OUT_DIR [--config YAML] [--calib FILE] [--topic T]
#                            [--max-frames N] [--start-frame N] [--quiet]
# DATASET: EuRoC ASL folder (top, mav0/ or mav0/cam0/), TUM folder (rgb.txt), KITTI
# odometry folder (image_0/ or image_l/ + calib.txt) or a .bag (needs --calib).
# Without --config, config/euroc.yaml, config/kitti.yaml or config/tum.yaml is
# picked by the dataset's kind. Outputs: OUT_DIR/trajectory.txt (TUM, T_w_c),
# OUT_DIR/stats.json, OUT_DIR/points.ply. VE_NO_BUILD=1 skips the build step.
# Every other flag goes to vitamin_e_run (--save-map, --log-frames, --pipelined, ...):
# `./scripts/run_dataset.sh DATASET OUT_DIR --help` lists them.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage="usage: ./scripts/run_dataset.sh DATASET OUT_DIR [--config YAML] [--calib FILE] [--topic T] [--max-frames N] [--start-frame N] [--quiet]"
# Only the first argument: a --help after DATASET OUT_DIR is vitamin_e_run's.
ve_help_on_request "${1:-}"
[ $# -ge 2 ] || ve_die "$usage"
dataset="$1"
out="$2"
shift 2
[ -e "$dataset" ] || ve_die "dataset '$dataset' does not exist"

# The dataset's kind, as vitamin_e::io::detectDatasetKind sees it.
kind=""
if [ -f "$dataset" ]; then
  case "$dataset" in *.bag) kind=rosbag ;; esac
elif [ -d "$dataset/mav0" ] || [ -d "$dataset/cam0" ] || [ -f "$dataset/data.csv" ]; then
  kind=euroc
elif [ -f "$dataset/rgb.txt" ]; then
  kind=tum
elif [ -d "$dataset/image_0" ] || [ -d "$dataset/image_l" ]; then
  kind=kitti
fi

config_args=()
has_config=0
for a in "$@"; do
  [ "$a" = --config ] && has_config=1
done
if [ "$has_config" = 0 ]; then
  case "$kind" in
    euroc | rosbag) config_args=(--config "$VE_ROOT/config/euroc.yaml") ;;  # EuRoC bags are the common case
    kitti) config_args=(--config "$VE_ROOT/config/kitti.yaml") ;;
    tum) config_args=(--config "$VE_ROOT/config/tum.yaml") ;;
  esac
fi

bin="$VE_WS/devel/lib/vitamin_e/vitamin_e_run"
if [ "${VE_NO_BUILD:-0}" != 1 ] || [ ! -x "$bin" ]; then
  mkdir -p "$VE_WS"
  log="$VE_WS/run_dataset_build.log"
  "$VE_ROOT/scripts/build.sh" --target vitamin_e_run >"$log" 2>&1 \
    || { tail -30 "$log" >&2; ve_die "building vitamin_e_run failed (log: $log)"; }
fi
[ -x "$bin" ] || ve_die "vitamin_e_run was not built ($bin missing)"

if [ -n "$kind" ]; then
  ve_info "$kind dataset '$dataset' -> '$out'${config_args[*]:+ (${config_args[*]})}"
fi
exec "$bin" --dataset "$dataset" --out "$out" "${config_args[@]}" "$@"
