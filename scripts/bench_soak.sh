#!/usr/bin/env bash
# Soak test: the SLAM system on the project's synthetic room (376x240, rendered
# in-process, no files) for a wall-clock time, resident memory sampled every N
# frames. Prints the curve (frame, minutes, RSS MB, map points, ...) and a
# verdict on whether memory is flat after warm-up (slope of the second half).
# Not part of the tests (it runs for an hour by default).
#   ./scripts/bench_soak.sh [--minutes M] [--sample-every N] [--width W --height H]
#                           [--archive-voxel V] [--max-frames F] [--seed S] [--realtime]
# --realtime: frames paced at 20 Hz, as from a camera (an hour = 72,000 frames).
# --help lists the options. Last line of the output: JSON summary. Exit 1 if a non-finite
# pose was seen, 2 on a bad option.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bin="$(ve_bench_bin bench_system_soak)"
exec "$bin" "$@"
