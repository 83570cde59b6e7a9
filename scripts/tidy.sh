#!/usr/bin/env bash
# clang-tidy with the checks of .clang-tidy (naming, bugprone-*, performance-*) on the whole
# tree: every translation unit of the build's compile_commands.json (src, test, bench) and the
# project's headers through them. Checks only, never edits a file.
#   ./scripts/tidy.sh [-j N] [REGEX]
# -j N: parallel clang-tidy processes (default: nproc). REGEX: only the files whose path
# matches it (e.g. 'src/pipeline/'). A full pass costs about 20 s of CPU per file (~50 CPU
# minutes for the tree): CI checks the files each commit changes (scripts/check_style.sh runs
# the same checks); this is the pass to run before a merge that touches many files.
# Exit 0: clean; 1: findings (listed once each, with their check); 2: cannot check.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
cd "$VE_ROOT"

jobs="$(nproc)"
filter='.*'
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -j) [ $# -ge 2 ] || ve_die "tidy.sh: -j needs a number"; shift; jobs="$1" ;;
    -*) ve_die "tidy.sh: unknown option '$1'" ;;
    *) filter="$1" ;;
  esac
  shift
done
runner="$(command -v run-clang-tidy || command -v run-clang-tidy-14 || true)"
[ -n "$runner" ] || ve_die "run-clang-tidy is not installed (./scripts/setup.sh installs clang-tidy)"
db_dir="$VE_WS/build"
[ -f "$db_dir/compile_commands.json" ] ||
  ve_die "no $db_dir/compile_commands.json: build first (./scripts/build.sh), then run tidy.sh again"

log=$(mktemp)
trap 'rm -f "$log"' EXIT
# The build sees this checkout through $VE_WS/src/vitamin_e: headers are reported under that path.
"$runner" -p "$db_dir" -j "$jobs" -quiet -header-filter='.*/vitamin_e/(include|src|test|bench)/.*' "$filter" 2>&1 |
  sed -r 's/\x1b\[[0-9;]*m//g' >"$log" || true
if grep -q -E 'error: ' "$log" && ! grep -q -E 'warning: ' "$log"; then
  grep -E 'error: ' "$log" | head -20 >&2
  ve_die "clang-tidy failed (see the errors above)"
fi
findings=$(grep -E '(warning|error): ' "$log" | sed -e "s|^$VE_WS/src/vitamin_e/||" -e "s|^$VE_ROOT/||" | sort -u || true)
files=$(grep -c -E '^clang-tidy' "$log" || true)
[ "$files" -gt 0 ] || ve_die "tidy.sh: no file of $db_dir/compile_commands.json matches '$filter'"
if [ -n "$findings" ]; then
  echo "$findings"
  echo "tidy: $(wc -l <<<"$findings") finding(s) in $files file(s) checked"
  exit 1
fi
echo "tidy: OK ($files file(s) checked)"
