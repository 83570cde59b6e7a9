#!/usr/bin/env bash
# Renders the 11 EuRoC trajectories with ../shared/tools/render_sequence.py (a
# benchmark helper: needs the shared folder beside the checkout) and writes the
# list file for ./scripts/evaluate_suite.sh.
#   ./scripts/render_euroc_suite.sh OUT_DIR [--duration-s S] [--start-s S] [--shared DIR] [--only NAME]
# Profiles as in the SLAM issue: constant exposure and 2 blur samples for *_01 and
# *_02; dark exposure and 4 blur samples for *_03, MH_04 and MH_05. Textures: the
# image folders under shared/data. A sequence already rendered is kept.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

[ $# -ge 1 ] || ve_die "usage: ./scripts/render_euroc_suite.sh OUT_DIR [--duration-s S] [--start-s S] [--shared DIR] [--only NAME]"
out="$1"; shift
duration=20
start=10
shared="$VE_ROOT/../shared"
only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --duration-s) duration="$2"; shift ;;
    --start-s) start="$2"; shift ;;
    --shared) shared="$2"; shift ;;
    --only) only="$2"; shift ;;
    *) ve_die "render_euroc_suite.sh: unknown option '$1'" ;;
  esac
  shift
done
tool="$shared/tools/render_sequence.py"
[ -f "$tool" ] || ve_die "no renderer at $tool (pass --shared DIR)"
mkdir -p "$out"
list="$out/suite.txt"
: > "$list.tmp"
for gt in "$shared"/data/euroc/groundtruth/*.txt; do
  name=$(basename "$gt" .txt)
  case "$name" in
    *_01_*|*_02_*) profile=constant; blur=2 ;;
    *) profile=dark; blur=4 ;;
  esac
  dir="$out/$name"
  echo "$name $dir" >> "$list.tmp"
  [ -n "$only" ] && [ "$only" != "$name" ] && continue
  if [ -f "$dir/groundtruth_cam0_tum.txt" ] && [ -f "$dir/mav0/cam0/data.csv" ]; then
    ve_info "$name: already rendered"
    continue
  fi
  ve_info "$name: rendering ${duration}s from ${start}s ($profile, blur $blur)"
  /usr/bin/python3 "$tool" --trajectory "$gt" --calib "$shared/data/euroc/cam0_sensor.yaml" \
    --textures "$shared/data/euroc/V1_01_easy_first95" "$shared/data/kitti/06_first51" \
    --exposure-profile "$profile" --blur-samples "$blur" --seed 0 \
    --start-s "$start" --duration-s "$duration" --out "$dir.part" > "$out/$name.log" 2>&1 \
    || { tail -5 "$out/$name.log" >&2; ve_die "$name: render failed (log: $out/$name.log)"; }
  rm -rf "$dir" && mv "$dir.part" "$dir"
done
mv "$list.tmp" "$list"
ve_info "list for evaluate_suite.sh: $list"
