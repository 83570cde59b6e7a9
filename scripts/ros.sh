#!/usr/bin/env bash
# Runs a ROS command (roslaunch, rosrun, rostest, rosbag, rostopic, ...) in the
# built workspace's environment, loopback-only, with logs inside the workspace.
#   ./scripts/ros.sh roslaunch vitamin_e euroc.launch bag:=FILE
set -eo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
# Only the first argument: the rest belongs to the ROS command (rostopic --help).
ve_help_on_request "${1:-}"
[ $# -ge 1 ] || ve_die "usage: ./scripts/ros.sh CMD [ARGS...]"
if [ ! -f "$VE_WS/devel/setup.bash" ]; then
  "$VE_ROOT/scripts/build.sh" >&2
fi
# roslaunch drops an argument with nothing after ':=' and silently uses its default: refuse it.
if [ "$1" = roslaunch ]; then
  for a in "${@:2}"; do
    if [[ "$a" =~ ^[A-Za-z_][A-Za-z0-9_]*:=$ ]]; then
      ve_die "roslaunch ignores '$a' (nothing after :=) and would use the default: give a value (e.g. imu_topic:=none for no IMU)"
    fi
  done
fi
ve_ros_env
exec "$@"
