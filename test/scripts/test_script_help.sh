#!/usr/bin/env bash
# Every script of scripts/ answers -h / --help with its usage and exit 0, and acts on nothing:
# no build, no install (the workspace is a folder that must not appear). Left out: the four bench
# scripts whose options are their benchmark binary's (their --help builds that binary first).
# Seconds, no data.
#   test_script_help.sh
set -uo pipefail
root="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/home"
fails=0
ok() { echo "ok: $1"; }
fail() { echo "FAIL: $1"; fails=$((fails + 1)); }

for script in "$root"/scripts/*.sh "$root"/scripts/*.py; do
  name="$(basename "$script")"
  case "$name" in
    common.sh | bench_ba.sh | bench_dense.sh | bench_soak.sh | bench_tracking.sh) continue ;;
  esac
  for flag in --help -h; do
    # Run as a user runs it: by its shebang (make_bag.sh is Python).
    VE_WS="$tmp/ws" HOME="$tmp/home" timeout 30 "$script" "$flag" >"$tmp/out" 2>"$tmp/err"
    rc=$?
    if [ $rc -ne 0 ]; then fail "$name $flag: exit $rc: $(head -c 300 "$tmp/err")"
    elif [ "$(grep -c . "$tmp/out")" -lt 2 ] && ! grep -qi usage "$tmp/out"; then
      fail "$name $flag: no usage printed: $(head -c 200 "$tmp/out")"
    else ok "$name $flag"; fi
  done
done
# A --help after the positional arguments belongs to the tool the script passes its flags to:
# run_dataset.sh must go on to vitamin_e_run's (here it stops first, at the missing dataset).
VE_WS="$tmp/ws" timeout 30 "$root/scripts/run_dataset.sh" "$tmp/no_such_dataset" "$tmp/out_dir" --help \
  >"$tmp/out" 2>"$tmp/err"
rc=$?
if [ $rc -ne 0 ] && grep -q "does not exist" "$tmp/err"; then ok "run_dataset.sh DATASET OUT --help is not the script's"
else fail "run_dataset.sh DATASET OUT --help: exit $rc, printed: $(head -c 200 "$tmp/out")"; fi
if [ -e "$tmp/ws" ]; then fail "--help made a workspace: $(find "$tmp/ws" | head -3)"; else ok "--help built nothing"; fi
[ $fails -eq 0 ] || { echo "$fails failure(s)"; exit 1; }
echo "all ok"
