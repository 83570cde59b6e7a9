#!/usr/bin/env bash
# The first command to try: builds vitamin_e, renders a ~20 s synthetic sequence
# with exact ground truth (once; reused afterwards), runs VITAMIN-E on it,
# evaluates the trajectory (Sim(3) ATE, plot) and prints the timing per stage.
#   ./scripts/demo.sh [--frames N] [--seed S] [--fresh]
# Then plays the sequence as a bag through the ROS nodelets (euroc.launch, headless).
# Outputs in demo_output/: sequence/ (EuRoC layout), run/ (trajectory.txt,
# stats.json, points.ply, mesh.ply), trajectory.png, evaluation.txt, ros/ (bag,
# trajectory, mesh of the ROS run). VE_NO_BUILD=1 skips the build, VE_NO_ROS=1 the ROS run.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

frames=400
seed=0
fresh=0
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) [ $# -ge 2 ] || ve_die "--frames needs a number"; frames="$2"; shift ;;
    --seed) [ $# -ge 2 ] || ve_die "--seed needs a number"; seed="$2"; shift ;;
    --fresh) fresh=1 ;;
    -h | --help) ve_print_header; exit 0 ;;
    *) ve_die "demo.sh: unknown option '$1' (--frames N, --seed S, --fresh)" ;;
  esac
  shift
done
[[ "$frames" =~ ^[0-9]+$ ]] && [ "$frames" -ge 10 ] || ve_die "--frames must be a number >= 10"

out="$VE_ROOT/demo_output"
seq="$out/sequence"
run="$out/run"
bin_dir="$VE_WS/devel/lib/vitamin_e"
py=/usr/bin/python3

if [ "${VE_NO_BUILD:-0}" != 1 ]; then
  ve_info "1/5 building (./scripts/build.sh)"
  "$VE_ROOT/scripts/build.sh" || ve_die "the build failed (see above)"
fi
for b in vitamin_e_make_sequence vitamin_e_evaluate; do
  [ -x "$bin_dir/$b" ] || ve_die "$bin_dir/$b is missing: build first (./scripts/build.sh)"
done

# 2. The sequence: reuse it if complete and made with the same settings.
settings="frames=$frames seed=$seed rate=20 size=752x480 distortion=euroc"
if [ "$fresh" = 1 ] || [ ! -f "$seq/.demo_settings" ] || [ "$(cat "$seq/.demo_settings")" != "$settings" ]; then
  ve_info "2/5 rendering $frames frames (752x480, 20 Hz, seed $seed) into $seq"
  rm -rf "$seq.partial"
  "$bin_dir/vitamin_e_make_sequence" --out "$seq.partial" --frames "$frames" --rate-hz 20 \
    --width 752 --height 480 --seed "$seed" --distortion euroc
  echo "$settings" >"$seq.partial/.demo_settings"
  rm -rf "$seq"
  mv "$seq.partial" "$seq"
else
  ve_info "2/5 reusing $seq ($settings; --fresh renders it again)"
fi

ve_info "3/5 running VITAMIN-E (./scripts/run_dataset.sh $seq $run)"
rm -rf "$run"
VE_NO_BUILD=1 "$VE_ROOT/scripts/run_dataset.sh" "$seq" "$run" \
  || ve_die "the run failed (see the messages above); nothing to evaluate"

traj="$run/trajectory.txt"
stats="$run/stats.json"
n_frames="$frames"
if [ -f "$stats" ]; then
  n_frames="$("$py" -c 'import json,sys; print(json.load(open(sys.argv[1])).get("frames", sys.argv[2]))' "$stats" "$frames")"
fi

ve_info "4/5 evaluating against the ground truth"
eval_ok=0
if [ ! -f "$traj" ] || ! grep -qv '^[[:space:]]*\(#.*\)\?$' "$traj"; then
  echo
  echo "The trajectory is empty: VITAMIN-E output no pose for the $n_frames frames"
  echo "(it never initialised or lost track at once). See $run and the messages above."
else
  if "$VE_ROOT/scripts/evaluate.sh" "$traj" "$seq/groundtruth_cam0_tum.txt" --frames "$n_frames" \
      --plot "$out/trajectory.png" >"$out/evaluation.txt"; then
    eval_ok=1
  else
    echo "evaluation failed: $(tail -n 1 "$out/evaluation.txt" 2>/dev/null)" >&2
  fi
fi

echo
echo "== VITAMIN-E on the synthetic demo sequence ($n_frames frames, 752x480, 20 Hz) =="
if [ "$eval_ok" = 1 ]; then
  grep -v '^{' "$out/evaluation.txt" | grep -E 'success|ATE|RPE|alignment' || true
  "$py" - "$(tail -n 1 "$out/evaluation.txt")" <<'PYEOF'
import json, sys
r = json.loads(sys.argv[1])
print("ATE RMSE %.2f cm (Sim(3) aligned, scale %.4f) over %d poses of %d frames"
      % (100 * r["ate_rmse_m"], r["scale"], r["matched"], r["frames"]))
PYEOF
  echo "plot: $out/trajectory.png"
fi
if [ -f "$stats" ]; then
  "$py" - "$stats" <<'PYEOF'
import json, sys
s = json.load(open(sys.argv[1]))
sr = s.get("success_rate")
print("frames %s, tracked %s (%s), init retries %s" % (s.get("frames"), s.get("tracked_frames"),
      "n/a" if sr is None else "%.1f %%" % (100 * sr), s.get("init_retries")))
t = s.get("timing_ms") or {}
if t:
    print("\n| stage | mean [ms] | median [ms] | p95 [ms] | count |")
    print("|---|---|---|---|---|")
    f = lambda v: "n/a" if v is None else "%.1f" % v
    for name, v in t.items():
        print("| %s | %s | %s | %s | %s |" % (name, f(v.get("mean")), f(v.get("median")), f(v.get("p95")), v.get("count")))
    if "total" in t and t["total"].get("mean"):
        m = t["total"]["mean"]
        print("\n%.1f ms/frame end to end: %s real time at 20 Hz (50 ms budget) on this machine (%s cores)"
              % (m, "within" if m < 50 else "NOT within", __import__("os").cpu_count()))
PYEOF
fi
[ "$eval_ok" = 1 ] || exit 1

# 5. The same sequence through ROS: a EuRoC-style bag played into the tracking and
# meshing nodelets (headless, at the camera rate), trajectory and mesh saved on
# shutdown. VE_NO_ROS=1 skips it.
if [ "${VE_NO_ROS:-0}" != 1 ]; then
  ve_info "5/5 the same through ROS: bag -> euroc.launch (nodelets, rate 1.0) -> trajectory and mesh"
  ros_out="$out/ros"
  rm -rf "$ros_out" && mkdir -p "$ros_out"
  "$VE_ROOT/scripts/make_bag.sh" "$seq" "$ros_out/sequence.bag" >"$ros_out/make_bag.log" 2>&1 \
    || ve_die "make_bag.sh failed (log: $ros_out/make_bag.log)"
  timeout 600 "$VE_ROOT/scripts/ros.sh" roslaunch vitamin_e euroc.launch bag:="$ros_out/sequence.bag" \
      rviz:=false calibration_file:="$seq/mav0/cam0/sensor.yaml" trajectory_file:="$ros_out/trajectory.txt" \
      mesh_file:="$ros_out/mesh.ply" </dev/null >"$ros_out/roslaunch.log" 2>&1 \
    || ve_die "roslaunch euroc.launch failed (log: $ros_out/roslaunch.log)"
  grep -E "frames processed|written to" "$ros_out/roslaunch.log" | sed 's/^/  /' || true
  if [ -s "$ros_out/trajectory.txt" ] && "$VE_ROOT/scripts/evaluate.sh" "$ros_out/trajectory.txt" \
      "$seq/groundtruth_cam0_tum.txt" --frames "$n_frames" >"$ros_out/evaluation.txt" 2>&1; then
    "$py" - "$(tail -n 1 "$ros_out/evaluation.txt")" <<'PYEOF'
import json, sys
r = json.loads(sys.argv[1])
print("ROS: ATE RMSE %.2f cm (Sim(3)) over %d poses of %d frames; outputs in demo_output/ros/"
      % (100 * r["ate_rmse_m"], r["matched"], r["frames"]))
PYEOF
  else
    ve_die "the ROS run wrote no trajectory (log: $ros_out/roslaunch.log)"
  fi
fi
