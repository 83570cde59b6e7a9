#!/usr/bin/env bash
# Runs vitamin_e on a list of sequences and prints the paper's table (Markdown).
#   ./scripts/evaluate_suite.sh LIST [--out DIR] [-- run_dataset.sh flags...]
# LIST: one sequence per line, `NAME DATASET_PATH [GROUNDTRUTH [SENSOR_YAML]]` ('#'
# comments; relative paths are taken from the repository's root, so
# config/suites/real.txt names ../shared/...: VE_SHARED=DIR puts it elsewhere, and
# ../renders/... is under VE_RENDERS=DIR, default ../renders). GROUNDTRUTH defaults to
# DATASET_PATH/groundtruth_cam0_tum.txt, else DATASET_PATH/poses.txt (KITTI), else
# the dataset's EuRoC ground truth (body pose, turned into the camera's with the
# dataset's own sensor.yaml). SENSOR_YAML: GROUNDTRUTH is a body pose, camera =
# body * T_BS of that file (e.g. the shared EuRoC TUM ground truth files).
# Each sequence runs `./scripts/run_dataset.sh DATASET OUT/NAME` (writes
# trajectory.txt and stats.json), then `./scripts/evaluate.sh` (Sim(3) ATE).
# OUT defaults to out/suite. The table also goes to OUT/results.md; OUT/run_info.txt
# records the command, commit, machine, start and end time and load, OUT/list.txt the
# list, OUT/NAME/load.txt the load before that run. A DATASET_PATH that does not exist
# is not run: OUT/NAME/missing.txt names it and its row says so (e.g. not rendered yet).
# Columns: success = tracked / all frames (the paper's); after init = tracked /
# frames from the first initialization on; init retries = new maps after a loss;
# relocalizations = losses recovered in the existing map; peak RSS of the whole run.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"

[ $# -ge 1 ] || ve_die "usage: ./scripts/evaluate_suite.sh LIST [--out DIR] [-- run_dataset.sh flags...]"
list="$1"; shift
out="$VE_ROOT/out/suite"
run_flags=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || ve_die "--out needs a folder"; out="$2"; shift ;;
    --) shift; run_flags=("$@"); break ;;
    *) ve_die "evaluate_suite.sh: unknown option '$1'" ;;
  esac
  shift
done
[ -f "$list" ] || ve_die "$list: no such list file"
mkdir -p "$out"
py=/usr/bin/python3
cp "$list" "$out/list.txt"

# What produced these results (read by ./scripts/results.sh).
ve_suite_info_begin "$out" ./scripts/evaluate_suite.sh "$list" --out "$out" ${run_flags[@]+-- "${run_flags[@]}"}

# Reads KEY (dotted path) from a JSON file; prints "" if absent.
json_get() {
  "$py" - "$1" "$2" <<'PYEOF'
import json, sys
try:
    with open(sys.argv[1]) as fh:
        v = json.load(fh)
    for k in sys.argv[2].split("."):
        v = v[k]
    print(v)
except Exception:
    print("")
PYEOF
}
# Reads KEY from a JSON text (one line) on stdin.
json_line_get() {
  "$py" -c 'import json,sys
try:
    v = json.loads(sys.stdin.read()).get(sys.argv[1], "")
    print("" if v is None else v)
except Exception:
    print("")' "$1"
}
fmt() { "$py" -c 'import sys
v = sys.argv[1]; s = float(sys.argv[2]); d = int(sys.argv[3])
print(("%%.%df" % d) % (float(v) * s) if v not in ("", "None") else "n/a")' "$1" "$2" "$3"; }

pct() { "$py" -c 'import sys; v = sys.argv[1]; print("%.2g" % float(v) if v not in ("", "None") else "n/a")' "$1"; }

rows=()
while read -r name dataset gt sensor rest; do
  [ -z "${name:-}" ] && continue
  case "$name" in \#*) continue ;; esac
  [ -n "${dataset:-}" ] || ve_die "$list: line for '$name' has no DATASET_PATH"
  dataset="$(ve_list_path "$dataset")"
  gt="$(ve_list_path "${gt:-}")"
  sensor="$(ve_list_path "${sensor:-}")"
  if [ -z "${gt:-}" ] && [ -f "$dataset/groundtruth_cam0_tum.txt" ]; then
    gt="$dataset/groundtruth_cam0_tum.txt"
  elif [ -z "${gt:-}" ] && [ -f "$dataset/poses.txt" ]; then
    gt="$dataset/poses.txt"
  elif [ -z "${gt:-}" ] && [ -f "$dataset/mav0/state_groundtruth_estimate0/data.csv" ]; then
    gt="$dataset/mav0/state_groundtruth_estimate0/data.csv"
  fi
  run="$out/$name"
  mkdir -p "$run"
  # Nothing of an earlier run in this folder may pass for this run's result.
  rm -f "$run/missing.txt" "$run/stats.json" "$run/trajectory.txt" "$run/evaluate.txt" "$run/evaluate.err"
  if [ ! -e "$dataset" ]; then
    ve_info "== $name: $dataset does not exist: not run"
    echo "$dataset" >"$run/missing.txt"
    rows+=("| $name | n/a | not run: $dataset does not exist | | | | | | | | |")
    continue
  fi
  ve_info "== $name: $dataset"
  cut -d ' ' -f 1-3 /proc/loadavg >"$run/load.txt"
  run_rc=0
  "$VE_ROOT/scripts/run_dataset.sh" "$dataset" "$run" "${run_flags[@]}" >"$run/run.log" 2>&1 </dev/null || run_rc=$?
  frames="$(json_get "$run/stats.json" frames)"
  retries="$(json_get "$run/stats.json" init_retries)"
  relocs="$(json_get "$run/stats.json" relocalizations)"
  ms="$(json_get "$run/stats.json" timing_ms.total.mean)"
  stats_success="$(json_get "$run/stats.json" success_rate)"
  after_init="$(json_get "$run/stats.json" success_after_init)"
  rss="$(json_get "$run/stats.json" peak_rss_mb)"
  ate="" ate_percent="" path="" success="$stats_success" note=""
  if [ "$run_rc" -ne 0 ]; then
    note="run failed (exit $run_rc, log: $run/run.log)"
  elif [ -z "${gt:-}" ]; then
    note="no ground truth"
  else
    eval_args=("$run/trajectory.txt" "$gt")
    [ -n "$frames" ] && eval_args+=(--frames "$frames")
    [ -n "${sensor:-}" ] && eval_args+=(--body-to-camera "$sensor")
    if json="$("$VE_ROOT/scripts/evaluate.sh" "${eval_args[@]}" 2>"$run/evaluate.err" | tee "$run/evaluate.txt" | tail -n 1)"; then
      ate="$(echo "$json" | json_line_get ate_rmse_m)"
      ate_percent="$(echo "$json" | json_line_get ate_path_percent)"
      path="$(echo "$json" | json_line_get path_length_m)"
      # Success as in the paper: tracked frames / all frames (stats.json); the
      # evaluator's matched poses / frames only when the run did not report it.
      [ -n "$success" ] || success="$(echo "$json" | json_line_get success_rate)"
    else
      note="evaluation failed: $(tail -n 1 "$run/evaluate.err")"
    fi
  fi
  ve_info "   ATE $(fmt "$ate" 100 2) cm, success $(fmt "$success" 100 1) %, retries ${retries:-n/a}, relocalizations ${relocs:-n/a}, $(fmt "$ms" 1 1) ms/frame ${note}"
  ate_cell="$(fmt "$ate" 100 2)"
  [ -n "$note" ] && ate_cell="n/a ($note)"
  # The paper counts a run under 90 % of frames tracked as a failure.
  if [ -z "$note" ] && [ -n "$success" ] && "$py" -c 'import sys; sys.exit(0 if float(sys.argv[1]) < 0.9 else 1)' "$success"; then
    ate_cell="fail ($ate_cell cm over $(fmt "$success" 100 1) % of frames)"
  fi
  rows+=("| $name | ${frames:-n/a} | $ate_cell | $(pct "$ate_percent") | $(fmt "$path" 1 1) | $(fmt "$success" 100 1) | $(fmt "$after_init" 100 1) | ${retries:-n/a} | ${relocs:-n/a} | $(fmt "$ms" 1 1) | $(fmt "$rss" 1 0) |")
done <"$list"

{
  echo "| sequence | frames | ATE [cm] | ATE [% of path] | path [m] | success [%] | after init [%] | init retries | relocalizations | ms/frame | peak RSS [MB] |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|"
  for r in "${rows[@]}"; do echo "$r"; done
} | tee "$out/results.md"
ve_suite_info_end "$out"
