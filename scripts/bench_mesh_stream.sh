#!/usr/bin/env bash
# Bytes per second of the mesher's ~mesh topic while a bag is played through
# euroc.launch (tracking + meshing nodelets, no rviz), measured by a subscriber
# that records the serialized size of every message (scripts/topic_bytes.py):
# what an rviz on another machine receives.
#   ./scripts/bench_mesh_stream.sh BAG [--out DIR] [--window S] [-- euroc.launch arguments]
# e.g. -- config_file:=$PWD/config/kitti.yaml calibration_file:=CALIB imu_topic:=
# Runs in its own ROS master (a free port), which ends with the launch. Prints the
# bytes per second in each --window (5 s) of wall time, over the run's thirds, and
# as the last line a JSON summary (also DIR/mesh_bytes.json).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
usage="usage: ./scripts/bench_mesh_stream.sh BAG [--out DIR] [--window S] [-- euroc.launch arguments]"
if ve_wants_help "${1:-}"; then echo "$usage"; exit 0; fi
[ $# -ge 1 ] || ve_die "$usage"
bag="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
shift
[ -f "$bag" ] || ve_die "bag '$bag' not found"
out="$(mktemp -d /tmp/ve_mesh_stream.XXXXXX)"
window=5
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || ve_die "--out needs a value"; out="$2"; shift 2 ;;
    --window) [ $# -ge 2 ] || ve_die "--window needs a value"; window="$2"; shift 2 ;;
    --) shift; break ;;
    *) ve_die "unknown option '$1' ($usage)" ;;
  esac
done
mkdir -p "$out"
out="$(cd "$out" && pwd)"
[ -f "$VE_WS/devel/setup.bash" ] || ve_die "$VE_WS is not built: ./scripts/build.sh"
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:$port"

launch_pid="" recorder_pid=""
cleanup() {
  [ -n "$recorder_pid" ] && kill -INT "$recorder_pid" 2>/dev/null || true
  [ -n "$launch_pid" ] && kill -INT "$launch_pid" 2>/dev/null || true
  wait 2>/dev/null || true
}
trap cleanup EXIT

ve_info "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$VE_ROOT/scripts/ros.sh" roslaunch -p "$port" vitamin_e euroc.launch bag:="$bag" rviz:=false "$@" \
  >"$out/launch.log" 2>&1 &
launch_pid=$!
# The recorder subscribes once the master is up, before the first mesh (the tracker
# needs its first map before anything is fused).
for _ in $(seq 1 300); do
  "$VE_ROOT/scripts/ros.sh" rostopic list >/dev/null 2>&1 && break
  kill -0 "$launch_pid" 2>/dev/null || { tail -20 "$out/launch.log" >&2; ve_die "the launch ended early"; }
  sleep 0.2
done
"$VE_ROOT/scripts/ros.sh" /usr/bin/python3 "$VE_ROOT/scripts/topic_bytes.py" /tsdf_meshing/mesh \
  "$out/mesh_bytes.json" --window "$window" >"$out/recorder.log" 2>&1 &
recorder_pid=$!
wait "$launch_pid" || true
launch_pid=""
kill -INT "$recorder_pid"
wait "$recorder_pid" || true
recorder_pid=""
ve_info "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
[ -f "$out/mesh_bytes.json" ] || { cat "$out/recorder.log" >&2; ve_die "no summary written"; }

/usr/bin/python3 - "$out/mesh_bytes.json" "$bag" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
print(f"bag {sys.argv[2]}: {s['messages']} messages on {s['topic']}, {s['bytes'] / 1e6:.2f} MB")
if s["messages"]:
    print(f"first to last message {s['first_to_last_s']:.1f} s, largest message {s['max_message_bytes'] / 1e6:.3f} MB")
    bps = s.get("bytes_per_s")
    if bps:
        print(f"mean {bps / 1e6:.3f} MB/s")
    w = s.get("bytes_per_s_by_window", [])
    print(f"MB/s per {s['window_s']:g} s window: " + " ".join(f"{x / 1e6:.3f}" for x in w))
    if "bytes_per_s_thirds" in s:
        print("MB/s by third of the run: " + " ".join(f"{x / 1e6:.3f}" for x in s["bytes_per_s_thirds"]))
keys = ("messages", "bytes", "first_to_last_s", "max_message_bytes", "bytes_per_s", "bytes_per_s_thirds")
print(json.dumps({k: s[k] for k in keys if k in s}))
PY
