#!/usr/bin/env bash
# The ROS tools a user meets first, on the built workspace (seconds, no master):
# ./scripts/ros.sh passes its arguments to the command (the README's `ros.sh rosrun ... --help`),
# refuses a roslaunch argument with nothing after ':=' (roslaunch would use the default
# silently), rosrun finds each executable once without walking into the workspace
# ("File system loop detected"), the ROS tools the docs name are there, and
# scripts/setup.sh installs the Debian packages that bring them.
#   test_ros_tools.sh WORKSPACE
set -uo pipefail
root="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export VE_WS="${1:?usage: test_ros_tools.sh WORKSPACE}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
ok() { echo "ok: $1"; }
fail() { echo "FAIL: $1"; fails=$((fails + 1)); }

"$root/scripts/ros.sh" rosrun vitamin_e vitamin_e_run --help >"$tmp/help.out" 2>"$tmp/help.err"
rc=$?
if [ $rc -eq 0 ] && grep -q "usage" "$tmp/help.out"; then ok "ros.sh rosrun vitamin_e vitamin_e_run --help"
else fail "ros.sh rosrun vitamin_e vitamin_e_run --help: exit $rc: $(head -c 400 "$tmp/help.err")"; fi
if grep -q -e "File system loop" -e "non-unique" -e "command not found" "$tmp/help.err"; then
  fail "rosrun warned: $(grep -e "File system loop" -e "non-unique" -e "command not found" "$tmp/help.err" | head -3)"
else ok "rosrun: no file system loop, one executable"; fi

"$root/scripts/ros.sh" roslaunch vitamin_e euroc.launch bag:=/nonexistent.bag imu_topic:= >"$tmp/empty.out" 2>&1
rc=$?
if [ $rc -eq 2 ] && grep -q "imu_topic:=" "$tmp/empty.out"; then ok "ros.sh refuses imu_topic:= (empty)"
else fail "ros.sh roslaunch ... imu_topic:= exit $rc (expected 2): $(head -c 300 "$tmp/empty.out")"; fi

# The tools of docs/ROS.md: rostopic echo of the odometry and markers (their Python message
# classes), tf's echo and the static publisher of REP-105's base -> camera.
if /usr/bin/python3 -c "import nav_msgs.msg, visualization_msgs.msg" 2>"$tmp/py.err"; then ok "nav_msgs and visualization_msgs for Python"
else fail "Python message classes: $(tail -1 "$tmp/py.err")"; fi
for tool in "tf2_ros static_transform_publisher" "tf tf_echo" "tf2_tools echo.py"; do
  set -- $tool
  if "$root/scripts/ros.sh" catkin_find --first-only "$1" "$2" 2>/dev/null | grep -q .; then ok "rosrun $1 $2 exists"
  else fail "rosrun $1 $2: not installed"; fi
done
for p in python3-nav-msgs python3-visualization-msgs tf2-tools tf-tools; do
  if grep -q -w -- "$p" "$root/scripts/setup.sh"; then ok "setup.sh installs $p"; else fail "setup.sh does not install $p"; fi
done

echo "$fails failure(s)"
[ "$fails" -eq 0 ]
