#!/usr/bin/env bash
# Map persistence on data: maps one sequence, saves the map, then localizes other
# sequences of the same scene in it (--load-map --localization-only) and scores them
# with the alignment fitted on the mapping run, unchanged (so the ATE shows that they
# are in the first run's frame and scale, not only that their shape is right).
#   ./scripts/evaluate_map_reuse.sh LIST [--out DIR] [-- run_dataset.sh flags...]
# LIST: `NAME DATASET [MAP_FROM]` per line ('#' comments; paths as in evaluate_suite.sh:
# ../shared/... under VE_SHARED, ../renders/... under VE_RENDERS). Without MAP_FROM the
# sequence is mapped (--save-map OUT/NAME/map.vemap) and scored with its own Sim(3); with
# MAP_FROM (an earlier NAME) it runs in that map and is scored with `./scripts/evaluate.sh
# OUT/NAME GT --alignment-from OUT/MAP_FROM/trajectory.txt --alignment-gt MAP_FROM's GT`.
# Ground truth: DATASET/groundtruth_cam0_tum.txt. Output layout as evaluate_suite.sh's
# (OUT/NAME/{stats.json,evaluate.txt,load.txt}, OUT/run_info.txt, OUT/list.txt), so
# ./scripts/results.sh formats it; OUT defaults to out/map_reuse.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage="usage: ./scripts/evaluate_map_reuse.sh LIST [--out DIR] [-- run_dataset.sh flags...]"
[ $# -ge 1 ] || ve_die "$usage"
ve_help_on_request "$@"
list="$1"; shift
out="$VE_ROOT/out/map_reuse"
run_flags=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] && [ -n "$2" ] || ve_die "--out needs a folder"; out="$2"; shift ;;
    --) shift; run_flags=("$@"); break ;;
    *) ve_die "evaluate_map_reuse.sh: unknown option '$1' ($usage)" ;;
  esac
  shift
done
[ -f "$list" ] || ve_die "$list: no such list file"
mkdir -p "$out"
cp "$list" "$out/list.txt"
ve_suite_info_begin "$out" ./scripts/evaluate_map_reuse.sh "$list" --out "$out" ${run_flags[@]+-- "${run_flags[@]}"}

declare -A gt_of
while read -r name dataset map_from rest; do
  [ -z "${name:-}" ] && continue
  case "$name" in \#*) continue ;; esac
  [ -n "${dataset:-}" ] || ve_die "$list: line for '$name' has no DATASET"
  dataset="$(ve_list_path "$dataset")"
  run="$out/$name"
  mkdir -p "$run"
  rm -f "$run/missing.txt" "$run/stats.json" "$run/trajectory.txt" "$run/evaluate.txt" "$run/evaluate.err" "$run/map.vemap"
  if [ ! -e "$dataset" ]; then
    ve_info "== $name: $dataset does not exist: not run"
    echo "$dataset" >"$run/missing.txt"
    continue
  fi
  gt="$dataset/groundtruth_cam0_tum.txt"
  gt_of[$name]="$gt"
  map_args=(--save-map "$run/map.vemap")
  eval_args=()
  if [ -n "${map_from:-}" ]; then
    [ -n "${gt_of[$map_from]:-}" ] || ve_die "$list: '$name' uses the map of '$map_from', which is not an earlier line that ran"
    map_args=(--load-map "$out/$map_from/map.vemap" --localization-only)
    eval_args=(--alignment-from "$out/$map_from/trajectory.txt" --alignment-gt "${gt_of[$map_from]}")
  fi
  ve_info "== $name: $dataset${map_from:+ in the map of $map_from}"
  cut -d ' ' -f 1-3 /proc/loadavg >"$run/load.txt"
  run_rc=0
  "$VE_ROOT/scripts/run_dataset.sh" "$dataset" "$run" "${map_args[@]}" ${run_flags[@]+"${run_flags[@]}"} \
    >"$run/run.log" 2>&1 </dev/null || run_rc=$?
  if [ "$run_rc" -ne 0 ]; then
    ve_info "   run failed (exit $run_rc, log: $run/run.log)"
    continue
  fi
  frames="$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1])).get("frames", ""))' "$run/stats.json" 2>/dev/null || true)"
  [ -n "$frames" ] && eval_args+=(--frames "$frames")
  if "$VE_ROOT/scripts/evaluate.sh" "$run/trajectory.txt" "$gt" ${eval_args[@]+"${eval_args[@]}"} \
      >"$run/evaluate.txt" 2>"$run/evaluate.err"; then
    ve_info "   $(tail -n 1 "$run/evaluate.txt")"
  else
    ve_info "   evaluation failed: $(tail -n 1 "$run/evaluate.err")"
  fi
done <"$list"
ve_suite_info_end "$out"
