#!/usr/bin/env bash
# Renders the 11 EuRoC trajectories with ../shared/tools/render_sequence.py (a
# benchmark helper: needs the shared folder beside the checkout) and writes the
# list file for ./scripts/evaluate_suite.sh.
#   ./scripts/render_euroc_suite.sh OUT_DIR [--full | --duration-s S --start-s S] [--shared DIR] [--only NAME]
# --full renders each whole sequence (as the paper's table and the anchors' peer runs
# did; about 10-25 min per sequence on 2 cores). Runs at nice 19 so that it stays
# out of the way of builds and timing benchmarks.
# Profiles as in the SLAM issue: constant exposure and 2 blur samples for *_01 and
# *_02; dark exposure and 4 blur samples for *_03, MH_04 and MH_05. Textures: the
# image folders under shared/data. A sequence already rendered is kept. One run at a time per
# OUT_DIR (a second one stops at once with a message).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"

[ $# -ge 1 ] || ve_die "usage: ./scripts/render_euroc_suite.sh OUT_DIR [--full | --duration-s S --start-s S] [--shared DIR] [--only NAME]"
out="$1"; shift
case "$out" in -*) ve_die "render_euroc_suite.sh: OUT_DIR comes first, got '$out' (--help for the usage)" ;; esac
duration=20
start=10
shared="$VE_ROOT/../shared"
only=""
full=0
while [ $# -gt 0 ]; do
  case "$1" in
    --duration-s) duration="$2"; shift ;;
    --start-s) start="$2"; shift ;;
    --shared) shared="$2"; shift ;;
    --only) only="$2"; shift ;;
    --full) full=1 ;;
    *) ve_die "render_euroc_suite.sh: unknown option '$1'" ;;
  esac
  shift
done
tool="$shared/tools/render_sequence.py"
[ -f "$tool" ] || ve_die "no renderer at $tool (pass --shared DIR)"
mkdir -p "$out"
# One render at a time per OUT_DIR: two would write the same .part folders and suite.txt, and the
# second to finish would delete the first's result.
exec 9> "$out/.render.lock"
flock -n 9 || ve_die "another render_euroc_suite.sh is writing to $out; wait for it to end or pick another OUT_DIR"
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
  if [ "$full" = 1 ]; then
    span=()
    ve_info "$name: rendering the whole sequence ($profile, blur $blur)"
  else
    span=(--start-s "$start" --duration-s "$duration")
    ve_info "$name: rendering ${duration}s from ${start}s ($profile, blur $blur)"
  fi
  nice -n 19 /usr/bin/python3 "$tool" --trajectory "$gt" --calib "$shared/data/euroc/cam0_sensor.yaml" \
    --textures "$shared/data/euroc/V1_01_easy_first95" "$shared/data/kitti/06_first51" \
    --exposure-profile "$profile" --blur-samples "$blur" --seed 0 \
    "${span[@]}" --out "$dir.part" > "$out/$name.log" 2>&1 \
    || { tail -5 "$out/$name.log" >&2; ve_die "$name: render failed (log: $out/$name.log)"; }
  rm -rf "$dir" && mv "$dir.part" "$dir"
done
mv "$list.tmp" "$list"
ve_info "list for evaluate_suite.sh: $list"
