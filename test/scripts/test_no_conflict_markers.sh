#!/usr/bin/env bash
# No file of the source tree holds a merge's conflict markers (a README once shipped with one):
# lines that start with 7 '<' or '>' followed by a space or the line's end, or that are exactly
# 7 '='. The workspaces (.ws*), .git and the output folders are not the source. Seconds.
#   test_no_conflict_markers.sh
set -uo pipefail
root="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
hits="$(grep -rInE --exclude-dir='.ws*' --exclude-dir=.git --exclude-dir=out --exclude-dir=demo_output \
  '^(<{7}|>{7})( |$)|^={7}$' "$root" | head -10)"
if [ -n "$hits" ]; then
  echo "FAIL: conflict markers:"
  echo "$hits"
  exit 1
fi
echo "ok: no conflict markers"
