#!/usr/bin/env bash
# Soak test: the SLAM system on the project's synthetic room (376x240, rendered
# in-process, no files) for a wall-clock time, resident memory sampled every N
# frames. Prints the curve (frame, minutes, RSS MB, map points, ...) and a
# verdict on whether memory is flat after warm-up (slope of the second half).
# Not part of the tests (it runs for an hour by default).
#   ./scripts/bench_soak.sh [--minutes M] [--sample-every N] [--width W --height H]
#                           [--archive-voxel V] [--max-frames F] [--seed S] [--realtime]
# --realtime: frames paced at 20 Hz, as from a camera (an hour = 72,000 frames).
# Last line of the output: JSON summary. Exit 1 if a non-finite pose was seen.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if [ $# -ge 1 ] && { [ "$1" = -h ] || [ "$1" = --help ]; }; then
  sed -n '2,9p' "$0"
  exit 0
fi
if [ "${VE_NO_BUILD:-0}" != 1 ]; then
  "$VE_ROOT/scripts/build.sh" --target bench_system_soak >&2
fi
bin="$VE_WS/devel/lib/vitamin_e/bench_system_soak"
[ -x "$bin" ] || ve_die "$bin is missing: build first (./scripts/build.sh --target bench_system_soak)"
exec "$bin" "$@"
