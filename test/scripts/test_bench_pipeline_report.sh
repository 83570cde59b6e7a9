#!/usr/bin/env bash
# Test of ./scripts/bench_pipeline_report.py (the table of bench_pipeline.sh) on made-up run
# folders (no data, seconds): fps from frames and wall time, the real-time factor from the
# trajectory's steps, process CPU per frame, medians over runs, pipelined/sequential efficiency.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
expect() {  # expect DESCRIPTION EXPECTED ACTUAL
  if [ "$2" = "$3" ]; then echo "ok: $1"; else echo "FAIL: $1: expected '$2', got '$3'"; fails=$((fails + 1)); fi
}

# run BUILD MODE RUN WALL_S USER_S [MINOR_FAULTS [SYS_S]]: 100 frames 0.1 s apart (a 10 Hz camera) in WALL_S seconds.
run() {
  local dir="$tmp/$1.kitti.$2.$3"
  mkdir -p "$dir"
  printf '{"frames": 100, "tracked_frames": 100, "init_retries": 0, "relocalizations": 0, "wall_time_s": %s,
  "timing_ms": {"tracking": {"mean": 9.5}, "total": {"mean": 20}}, "cpu_ms": {"tracking": 9.0, "mapping": 7.5},
  "dense": {"fused": 98, "dropped": 0}}\n' "$4" >"$dir/stats.json"
  awk 'BEGIN { for (i = 0; i < 100; ++i) printf "%.1f 0 0 0 0 0 0 1\n", 100 + 0.1 * i }' >"$dir/trajectory.txt"
  echo "${6:-1000} $5 ${7:-0.0} $4" >"$dir.time"
  [ -z "${8:-}" ] || printf '{"ate_rmse_m":%s,"matched":100}\n' "$8" >"$dir.ate.json"
}
# new: sequential 4 s and 5 s (25 and 20 fps: median 22.5), pipelined 2 s twice (50 fps).
run new sequential 1 4 4.0 2000 0.1
run new sequential 2 5 4.7 4000 0.2
run new pipelined 1 2 4.0 1000 0.0 0.20
run new pipelined 2 2 4.2 1000 0.0 0.10
# base: sequential 5 s, pipelined 4 s (20 and 25 fps).
run base sequential 1 5 5
run base sequential 2 5 5
run base pipelined 1 4 5.5
run base pipelined 2 4 5.5

out="$(python3 "$root/scripts/bench_pipeline_report.py" "$tmp" 2 "new base" "sequential pipelined" "kitti")"
json="$(tail -n 1 <<<"$out")"
get() { python3 -c "import json, sys; r = json.loads(sys.argv[1]); print(eval(sys.argv[2]))" "$json" "$1"; }
expect "median fps over the runs" "22.5" "$(get "round(r['sets']['kitti']['new']['sequential']['fps'], 3)")"
expect "pipelined fps" "50.0" "$(get "round(r['sets']['kitti']['new']['pipelined']['fps'], 3)")"
expect "real-time factor at 10 Hz" "5.0" "$(get "round(r['sets']['kitti']['new']['pipelined']['rt'], 3)")"
expect "efficiency" "2.222" "$(get "round(r['sets']['kitti']['new']['pipelined']['efficiency'], 3)")"
expect "base efficiency" "1.25" "$(get "round(r['sets']['kitti']['base']['pipelined']['efficiency'], 3)")"
expect "process CPU ms per frame (median)" "45.0" "$(get "round(r['sets']['kitti']['new']['sequential']['cpu_ms_per_frame'], 3)")"
expect "minor page faults per frame (median)" "30.0" "$(get "round(r['sets']['kitti']['new']['sequential']['faults_per_frame'], 3)")"
expect "kernel CPU ms per frame (median)" "1.5" "$(get "round(r['sets']['kitti']['new']['sequential']['sys_ms_per_frame'], 3)")"
expect "CPU ms by thread stage" "7.5" "$(get "r['sets']['kitti']['new']['pipelined']['cpu_ms']['mapping']")"
expect "the table has a row per build and mode" "4" "$(grep -cE '^(new|base) +(sequential|pipelined)' <<<"$out")"
expect "ATE median over the runs [cm]" "15.0" "$(get "round(r['sets']['kitti']['new']['pipelined']['ate_cm'], 3)")"
expect "ATE of each run in the table" "1" "$(grep -cE '^new +pipelined .*\| 20\.00/10\.00$' <<<"$out")"
expect "no ATE without a ground truth" "False" "$(get "'ate_cm' in r['sets']['kitti']['base']['pipelined']")"
expect "new/base line" "new/base fps, pipelined: 2.00" "$(grep 'new/base fps, pipelined' <<<"$out")"

[ "$fails" = 0 ] || { echo "$fails failure(s)"; exit 1; }
echo "all passed"
