#!/usr/bin/env bash
# Evaluates an estimated trajectory against ground truth (Sim(3)-aligned ATE,
# RPE, success rate) with vitamin_e_evaluate, building it if needed.
#   ./scripts/evaluate.sh TRAJECTORY GROUNDTRUTH [--frames N] [--plot OUT.png] [vitamin_e_evaluate flags...]
# TRAJECTORY: a trajectory file (TUM, EuRoC csv, KITTI) or a run folder with trajectory.txt.
# GROUNDTRUTH: TUM / EuRoC csv / KITTI poses, or a dataset folder. Other flags
# (--max-dt S, --body-to-camera YAML, --se3, --json, --aligned-out F, ...) are
# passed through (`./scripts/evaluate.sh TRAJECTORY GROUNDTRUTH --help` lists them). The last
# line printed is the JSON result.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
# Only the first argument: a --help after TRAJECTORY GROUNDTRUTH is vitamin_e_evaluate's.
ve_help_on_request "${1:-}"

[ $# -ge 2 ] || ve_die "usage: ./scripts/evaluate.sh TRAJECTORY GROUNDTRUTH [--frames N] [--plot OUT.png] [flags...]"
traj="$1"; gt="$2"; shift 2
plot=""
aligned=""
pass=()
while [ $# -gt 0 ]; do
  case "$1" in
    --plot) [ $# -ge 2 ] || ve_die "--plot needs a file"; plot="$2"; shift ;;
    --aligned-out) [ $# -ge 2 ] || ve_die "--aligned-out needs a file"; aligned="$2"; pass+=("$1" "$2"); shift ;;
    *) pass+=("$1") ;;
  esac
  shift
done

[ -e "$traj" ] || ve_die "$traj: no such trajectory file"
# A run folder (run_dataset.sh output) stands for its trajectory.txt.
if [ -d "$traj" ]; then
  [ -f "$traj/trajectory.txt" ] || ve_die "$traj: a folder without trajectory.txt"
  traj="$traj/trajectory.txt"
fi
[ -e "$gt" ] || ve_die "$gt: no such ground-truth file or folder"
if ! grep -qv '^[[:space:]]*\(#.*\)\?$' "$traj"; then
  ve_die "$traj: the trajectory is empty (no poses): the run tracked no frame, nothing to evaluate"
fi

bin="$VE_WS/devel/lib/vitamin_e/vitamin_e_evaluate"
# Build when the binary is missing or older than its sources.
need_build=0
if [ ! -x "$bin" ]; then
  need_build=1
elif [ -n "$(find "$VE_ROOT/src/eval" "$VE_ROOT/include/vitamin_e/eval" "$VE_ROOT/src/apps/vitamin_e_evaluate.cpp" \
             -newer "$bin" -print -quit 2>/dev/null)" ]; then
  need_build=1
fi
if [ "$need_build" = 0 ]; then
  :
elif ! "$VE_ROOT/scripts/build.sh" --target vitamin_e_evaluate >"${TMPDIR:-/tmp}/ve_evaluate_build.$$.log" 2>&1; then
  if [ -x "$bin" ]; then
    ve_info "build of vitamin_e_evaluate failed (log: ${TMPDIR:-/tmp}/ve_evaluate_build.$$.log); using the existing binary"
  else
    tail -20 "${TMPDIR:-/tmp}/ve_evaluate_build.$$.log" >&2
    ve_die "cannot build vitamin_e_evaluate"
  fi
else
  rm -f "${TMPDIR:-/tmp}/ve_evaluate_build.$$.log"
fi

if [ -z "$plot" ]; then
  exec "$bin" "$traj" "$gt" "${pass[@]}"
fi

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
extra=(--gt-out "$tmp/gt.txt" --errors-out "$tmp/errors.txt")
if [ -z "$aligned" ]; then
  aligned="$tmp/aligned.txt"
  extra+=(--aligned-out "$aligned")
fi
"$bin" "$traj" "$gt" "${pass[@]}" "${extra[@]}" | tee "$tmp/out.txt"
rc=${PIPESTATUS[0]}
[ "$rc" -eq 0 ] || exit "$rc"
mkdir -p "$(dirname "$plot")"
"$VE_ROOT/scripts/plot_trajectory.py" --gt "$tmp/gt.txt" --estimate "$aligned" --errors "$tmp/errors.txt" \
  --out "$plot" --title "$(basename "$traj") vs $(basename "$gt")" >&2
