#!/usr/bin/env bash
# clang-tidy with the checks of .clang-tidy (naming, bugprone-*, performance-*) on the whole
# tree: every translation unit of the build's compile_commands.json (src, test, bench) and the
# project's headers through them. Checks only, never edits a file. CI runs it (.ci/run).
#   ./scripts/tidy.sh [-j N] [--no-cache] [REGEX]
# -j N: parallel clang-tidy processes (default: nproc). REGEX: only the units whose path
# matches it (e.g. 'src/pipeline/'). A unit's result is cached under
# ${XDG_CACHE_HOME:-~/.cache}/vitamin_e/tidy/, keyed by what it depends on (scripts/tidy_tree.py
# says what); --no-cache checks every unit again.
# Exit 0: clean; 1: findings (listed once each, with their check); 2: cannot check.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
cd "$VE_ROOT"
ve_help_on_request "$@"
clang_tidy=$(ve_clang_tidy)
exec /usr/bin/python3 "$VE_ROOT/scripts/tidy_tree.py" --clang-tidy "$clang_tidy" "$@"
