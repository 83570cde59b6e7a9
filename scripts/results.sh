#!/usr/bin/env bash
# Writes docs/RESULTS.md (and the results table of README.md) from the evaluation suites.
#   ./scripts/results.sh [--out DIR] [--suites LIST] [--doc FILE] [--readme FILE | --no-readme] [-- run_dataset.sh flags...]
#   ./scripts/results.sh --from DIR [--suites LIST] [--doc FILE] [--readme FILE | --no-readme]
# Without --from: runs `./scripts/evaluate_suite.sh config/suites/SUITE.txt --out DIR/SUITE`
# for each suite (evaluate_map_reuse.sh for map_reuse; DIR default out/results), then writes
# the tables. --from DIR: only writes the tables from an earlier DIR (nothing is run).
# LIST: comma-separated suite names of config/suites/ (default
# real,renders_short,renders_full,map_reuse). Data roots: VE_SHARED (default ../shared) for the
# KITTI clips, VE_RENDERS (default ../renders) for the renders; a sequence whose data is
# missing gets a row saying so. Peers' numbers: config/suites/peers.txt.
# --doc default docs/RESULTS.md; --readme default README.md (the block between its
# "results.sh: begin/end" comments), --no-readme leaves it alone.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage="usage: ./scripts/results.sh [--out DIR | --from DIR] [--suites LIST] [--doc FILE] [--readme FILE | --no-readme] [-- run_dataset.sh flags...]"
out=""
from=""
suites="real,renders_short,renders_full,map_reuse"
doc="$VE_ROOT/docs/RESULTS.md"
readme="$VE_ROOT/README.md"
run_flags=()
orig_args=("$@")
need_value() { [ $# -ge 2 ] && [ -n "$2" ] && [ "${2#-}" = "$2" ]; }
while [ $# -gt 0 ]; do
  case "$1" in
    -h | --help) ve_print_header; exit 0 ;;
    --out) need_value "$@" || ve_die "--out needs a folder"; out="$2"; shift ;;
    --from) need_value "$@" || ve_die "--from needs a folder"; from="$2"; shift ;;
    --suites) need_value "$@" || ve_die "--suites needs a comma-separated list"; suites="$2"; shift ;;
    --doc) need_value "$@" || ve_die "--doc needs a file"; doc="$2"; shift ;;
    --readme) need_value "$@" || ve_die "--readme needs a file"; readme="$2"; shift ;;
    --no-readme) readme="" ;;
    --) shift; run_flags=("$@"); break ;;
    *) ve_die "results.sh: unknown option '$1' ($usage)" ;;
  esac
  shift
done
[ -z "$out" ] || [ -z "$from" ] || ve_die "--out runs the suites, --from only formats: give one of them"
[ -z "$from" ] || [ ${#run_flags[@]} -eq 0 ] || ve_die "--from runs nothing: run_dataset.sh flags after -- need --out"
IFS=',' read -r -a suite_names <<<"$suites"
[ ${#suite_names[@]} -gt 0 ] || ve_die "--suites is empty"
for s in "${suite_names[@]}"; do
  [[ "$s" =~ ^[A-Za-z0-9_.-]+$ ]] || ve_die "--suites: bad suite name '$s'"
  [ -f "$VE_ROOT/config/suites/$s.txt" ] || [ -n "$from" ] || ve_die "--suites: no list config/suites/$s.txt"
done
[ -z "$readme" ] || [ -f "$readme" ] || ve_die "$readme: no such file (--readme FILE or --no-readme)"

# The command line as typed, with the data roots, for the header.
cmd="./scripts/results.sh"
[ ${#orig_args[@]} -gt 0 ] && cmd="$cmd$(printf ' %q' "${orig_args[@]}")"
env_prefix=""
[ -n "${VE_SHARED:-}" ] && env_prefix+="VE_SHARED=$VE_SHARED "
[ -n "${VE_RENDERS:-}" ] && env_prefix+="VE_RENDERS=$VE_RENDERS "

if [ -z "$from" ]; then
  out="${out:-$VE_ROOT/out/results}"
  mkdir -p "$out"
  out="$(cd "$out" && pwd)"
  echo "$env_prefix$cmd" >"$out/results_command.txt"
  cd "$VE_ROOT"
  for s in "${suite_names[@]}"; do
    ve_info "suite $s -> $out/$s"
    args=("config/suites/$s.txt" --out "$out/$s")
    [ ${#run_flags[@]} -gt 0 ] && args+=(-- "${run_flags[@]}")
    script=evaluate_suite.sh
    [ "$s" = map_reuse ] && script=evaluate_map_reuse.sh
    "$VE_ROOT/scripts/$script" "${args[@]}" >/dev/null \
      || ve_info "suite $s: $script failed (exit $?); its rows say what is missing"
  done
  from="$out"
fi
[ -d "$from" ] || ve_die "$from: no such folder (the --out folder of an earlier ./scripts/results.sh)"

/usr/bin/python3 "$VE_ROOT/scripts/format_results.py" --from "$from" --suites "$suites" \
  --suite-dir "$VE_ROOT/config/suites" --peers "$VE_ROOT/config/suites/peers.txt" \
  --doc "$doc" ${readme:+--readme "$readme"} --command "$env_prefix$cmd"
ve_info "wrote $doc${readme:+ and the results table of $readme}"
