#!/usr/bin/env bash
# live.launch (tracking + meshing nodelets) fed by `rosbag play` of a 20 Hz bag WITHOUT --clock,
# as a camera would feed it: for the sequential and the pipelined tracker (~pipelined), on the
# machine as it is ("idle") and with one core kept busy by `yes > /dev/null` ("busy"), it measures
#   drops     % of the bag's images that got no /tracking/status (the live queue keeps the newest)
#   reloc     relocalizations and re-initializations (the last status)
#   latency   p50 / p95 [ms]: wall time from an image's arrival at the benchmark's node to the
#             arrival of the tracker's pose for that image (~pose; one process, one clock: what a
#             consumer of the poses sees; the bag's stamps are not wall time without --clock);
#             and p95 to the arrival of its status, which follows the frame's map work
#   tracked   frames with a pose / frames processed
#   ./scripts/bench_live.sh [--render DIR | --bag BAG --calibration YAML] [--modes sequential,pipelined]
#                           [--loads idle,busy] [--runs N] [--out DIR]
# Defaults: V1_01_easy_30s under VE_RENDERS (../renders), made into OUT/<name>.bag with
# scripts/make_bag.sh once; config/euroc.yaml; 1 run of each. Runs alternate (mode by mode within
# a load) so that both trackers see the same machine. Prints a markdown table, `uptime` before
# and after, and a JSON line with every number. Timing only: never part of the tests.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"
[ "${VE_NO_BUILD:-0}" = 1 ] || "$VE_ROOT/scripts/build.sh" >&2
ve_ros_env
exec /usr/bin/python3 "$VE_ROOT/scripts/bench_live.py" --default-render "$(ve_list_path ../renders/V1_01_easy_30s)" \
  --make-bag "$VE_ROOT/scripts/make_bag.sh" --default-out "$VE_WS/bench_live" "$@"
