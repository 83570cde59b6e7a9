#!/usr/bin/env bash
# Rewrites the tracking nodelet's parameter table in docs/ROS.md from the code
# (src/ros/tracking_params.cpp, through vitamin_e_ros_params --markdown); the text
# between the table's markers is replaced, the rest of the file is kept.
# test_ros_tracking_params checks that the doc is current.
#   ./scripts/update_ros_docs.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"
bin="$(ve_bench_bin vitamin_e_ros_params)"
table="$("$bin" --markdown)"
/usr/bin/python3 - "$VE_ROOT/docs/ROS.md" "$table" <<'PY'
import sys
path, table = sys.argv[1], sys.argv[2] + "\n"
text = open(path).read()
begin_marker, end_marker = table.splitlines()[0], table.rstrip("\n").splitlines()[-1]
b = text.find(begin_marker)
e = text.find(end_marker, b if b >= 0 else 0)
if b < 0 or e < 0:
    sys.exit("update_ros_docs.sh: %s has no generated table between its markers" % path)
e += len(end_marker) + 1
open(path, "w").write(text[:b] + table + text[e:])
print("docs/ROS.md: parameter table updated")
PY
