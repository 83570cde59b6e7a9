#!/usr/bin/env bash
# Runs a ROS command (roslaunch, rosrun, rostest, rosbag, rostopic, ...) in the
# built workspace's environment, loopback-only, with logs inside the workspace.
#   ./scripts/ros.sh roslaunch vitamin_e euroc.launch bag:=FILE
set -eo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
[ $# -ge 1 ] || ve_die "usage: ./scripts/ros.sh CMD [ARGS...]"
if [ ! -f "$VE_WS/devel/setup.bash" ]; then
  "$VE_ROOT/scripts/build.sh" >&2
fi
set +u
source "$VE_WS/devel/setup.bash"
export ROS_IP=127.0.0.1
export ROS_HOSTNAME=localhost
unset ROS_IPV6
export ROS_HOME="${ROS_HOME:-$VE_WS/ros_home}"
export ROS_LOG_DIR="${ROS_LOG_DIR:-$VE_WS/ros_home/log}"
mkdir -p "$ROS_LOG_DIR"
exec "$@"
