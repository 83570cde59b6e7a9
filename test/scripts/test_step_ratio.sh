#!/usr/bin/env bash
# Test of ./scripts/step_ratio.py on made-up trajectories (no data, seconds): a map
# whose scale doubles halfway shows ratios 0.5 then 1 (normalized on the second
# half), with KITTI and TUM ground truth; bad input gives one step_ratio: line and a
# non-zero exit code.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
expect() {  # expect DESCRIPTION EXPECTED ACTUAL
  if [ "$2" = "$3" ]; then echo "ok: $1"; else echo "FAIL: $1: expected '$2', got '$3'"; fails=$((fails + 1)); fi
}

# 20 frames, 1 m per frame along z; times 0.1 s apart (times.txt lists 5 more frames, as a clip's may).
mkdir -p "$tmp/kitti"
awk 'BEGIN { for (i = 0; i < 25; ++i) printf "%.6e\n", i * 0.1 }' >"$tmp/kitti/times.txt"
awk 'BEGIN { for (i = 0; i < 20; ++i) printf "1 0 0 0 0 1 0 0 0 0 1 %d\n", i }' >"$tmp/kitti/poses.txt"
awk 'BEGIN { for (i = 0; i < 20; ++i) printf "%.6f 0 0 %d 0 0 0 1\n", i * 0.1, i }' >"$tmp/gt_tum.txt"
# the estimate: 0.5 units per metre up to frame 10, then 1 unit per metre
awk 'BEGIN { for (i = 0; i < 20; ++i) printf "%.6f 0 0 %.3f 0 0 0 1\n", i * 0.1, i <= 10 ? 0.5 * i : 5 + (i - 10) }' \
  >"$tmp/est.txt"
step="$root/scripts/step_ratio.py"
expect "KITTI ground truth" "5:0.50 10:0.50 15:1.00" "$("$step" "$tmp/est.txt" "$tmp/kitti/poses.txt" --normalize 11:19)"
expect "a dataset folder" "5:0.50 10:0.50 15:1.00" "$("$step" "$tmp/est.txt" "$tmp/kitti" --normalize 11:19)"
expect "TUM ground truth, step 2" "2:0.50 4:0.50 6:0.50 8:0.50 10:0.50 12:1.00 14:1.00 16:1.00 18:1.00" \
  "$("$step" "$tmp/est.txt" "$tmp/gt_tum.txt" --step 2 --normalize 12:18)"

bad() {  # bad DESCRIPTION ARGS...: exit code != 0 and one step_ratio: line on stderr
  local desc="$1"; shift
  if "$step" "$@" >"$tmp/out" 2>"$tmp/err"; then
    echo "FAIL: $desc: exit code 0"; fails=$((fails + 1)); return
  fi
  if [ "$(grep -c '^step_ratio: ' "$tmp/err")" = 1 ] && [ "$(wc -l <"$tmp/err")" = 1 ]; then
    echo "ok: $desc"
  else
    echo "FAIL: $desc: stderr was:"; cat "$tmp/err"; fails=$((fails + 1))
  fi
}
bad "missing trajectory" "$tmp/none.txt" "$tmp/kitti"
bad "missing ground truth" "$tmp/est.txt" "$tmp/none"
bad "not a trajectory" "$tmp/kitti/times.txt" "$tmp/kitti"
bad "step 0" "$tmp/est.txt" "$tmp/kitti" --step 0
bad "bad --normalize" "$tmp/est.txt" "$tmp/kitti" --normalize x
bad "no step in the normalize range" "$tmp/est.txt" "$tmp/kitti" --normalize 100:200
rm "$tmp/kitti/times.txt"
bad "KITTI poses without times.txt" "$tmp/est.txt" "$tmp/kitti/poses.txt"

[ "$fails" = 0 ] || { echo "$fails check(s) failed"; exit 1; }
echo "all checks passed"
