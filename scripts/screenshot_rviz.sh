#!/usr/bin/env bash
# Renders rviz (rviz/vitamin_e.rviz) headless under Xvfb and saves a screenshot.
#   ./scripts/screenshot_rviz.sh OUT.png [--bag FILE [--rate R] [--launch-arg NAME:=VALUE ...]]
#                                [--wait S] [--rviz FILE] [--size WxH]
# With --bag, runs launch/euroc.launch on the bag (own master on a free port)
# and shoots after --wait seconds (default 20); without it, rviz connects to the
# running master ($ROS_MASTER_URI), e.g. a euroc.launch started beforehand.
set -eo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"

out=""
bag=""
rate="1.0"
launch_args=()
wait_s=20
rviz_cfg="$VE_ROOT/rviz/vitamin_e.rviz"
size="1280x800"
while [ $# -gt 0 ]; do
  case "$1" in
    --bag) shift; bag="$1" ;;
    --rate) shift; rate="$1" ;;
    --launch-arg) shift; launch_args+=("$1") ;;
    --wait) shift; wait_s="$1" ;;
    --rviz) shift; rviz_cfg="$1" ;;
    --size) shift; size="$1" ;;
    -*) ve_die "screenshot_rviz.sh: unknown option '$1'" ;;
    *) [ -z "$out" ] || ve_die "screenshot_rviz.sh: one output file"; out="$1" ;;
  esac
  shift
done
[ -n "$out" ] || ve_die "usage: ./scripts/screenshot_rviz.sh OUT.png [--bag FILE] [--wait S] [--rviz FILE] [--size WxH]"
[ -f "$VE_WS/devel/setup.bash" ] || "$VE_ROOT/scripts/build.sh" >&2
ve_ros_env
set +u

pids=()
cleanup() {
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill -INT "${pids[$i]}" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "${pids[$i]}" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "${pids[$i]}" 2>/dev/null || true
  done
}
trap cleanup EXIT

# A free X display.
display=99
while [ -e "/tmp/.X${display}-lock" ] || [ -e "/tmp/.X11-unix/X${display}" ]; do display=$((display + 1)); done
Xvfb ":$display" -screen 0 "${size}x24" -nolisten tcp >"$ROS_LOG_DIR/xvfb.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do xdpyinfo -display ":$display" >/dev/null 2>&1 && break; sleep 0.1; done
xdpyinfo -display ":$display" >/dev/null 2>&1 || ve_die "Xvfb :$display did not start (log: $ROS_LOG_DIR/xvfb.log)"

if [ -n "$bag" ]; then
  port=$((11400 + RANDOM % 500))
  export ROS_MASTER_URI="http://localhost:$port"
  roslaunch -p "$port" vitamin_e euroc.launch bag:="$bag" rviz:=false rate:="$rate" "${launch_args[@]}" </dev/null >"$ROS_LOG_DIR/screenshot_launch.log" 2>&1 &
  pids+=($!)
fi

DISPLAY=":$display" rviz -d "$rviz_cfg" >"$ROS_LOG_DIR/screenshot_rviz.log" 2>&1 &
pids+=($!)
ve_info "rviz on :$display, shooting in ${wait_s}s"
sleep "$wait_s"  # let rviz render what arrives
kill -0 "${pids[-1]}" 2>/dev/null || ve_die "rviz exited (log: $ROS_LOG_DIR/screenshot_rviz.log)"
xwd -root -display ":$display" | /usr/bin/convert xwd:- "$out"
ve_info "wrote $out"
