#!/usr/bin/env bash
# Do two builds give the same trajectories? Runs vitamin_e_run of both (sequential mode, which is
# deterministic) on the regression set and compares the md5 of their trajectory.txt: a refactoring
# must keep every one; a change of behaviour says which it changes.
#   ./scripts/regression_md5.sh BASE_BIN_DIR NEW_BIN_DIR [--only NAME]... [--work DIR] [--keep] [--base-configs DIR]
# BIN_DIR: a folder with vitamin_e_run (e.g. .ws/devel/lib/vitamin_e, or a copy of it made before
# the change). The set: the real KITTI clips 06_first51, 07_first160, 02_first300 (config/kitti.yaml,
# under VE_SHARED, default ../shared), the synthetic room (config/euroc.yaml) and the street turn
# and fast clips (config/kitti.yaml) made by BASE's vitamin_e_make_sequence (cached in
# WORK/sequences), and the short renders V1_01_easy_30s, V1_03_difficult_20s (config/euroc.yaml,
# under VE_RENDERS, default ../renders). Data that is missing is reported and skipped.
# WORK (default /tmp/vitamin_e_regression) keeps the sequences and the md5 of every run, keyed by
# the md5 of the executable, of the config and of the dataset's file list (names, sizes, times):
# a binary is run once per case;
# runs go to WORK/runs (deleted unless --keep). Prints one line per case and exits 1 when a
# trajectory differs.
# --base-configs DIR: BASE runs the configs in DIR (e.g. its own commit's: `git show
#   REV:config/kitti.yaml > DIR/kitti.yaml`, the same for euroc.yaml), NEW the checkout's.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

usage() { sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'; }
ve_wants_help "$@" && { usage; exit 0; }
[ $# -ge 2 ] || { usage >&2; exit 2; }
base_bin="$(cd "$1" && pwd)" new_bin="$(cd "$2" && pwd)"
shift 2
work=/tmp/vitamin_e_regression
keep=0
base_configs="$VE_ROOT/config"
only=()
while [ $# -gt 0 ]; do
  case "$1" in
    --only) shift; only+=("$1") ;;
    --work) shift; work="$1" ;;
    --keep) keep=1 ;;
    --base-configs) shift; base_configs="$(cd "$1" && pwd)" ;;
    *) ve_die "regression_md5.sh: unknown option '$1'" ;;
  esac
  shift
done
for b in "$base_bin" "$new_bin"; do [ -x "$b/vitamin_e_run" ] || ve_die "no vitamin_e_run in $b"; done

shared="${VE_SHARED:-$VE_ROOT/../shared}"
renders="${VE_RENDERS:-$VE_ROOT/../renders}"
seqs="$work/sequences"
runs="$work/runs"
cache="$work/md5_cache"
mkdir -p "$seqs" "$runs" "$cache"

# NAME DATASET CONFIG [make_sequence arguments: made into DATASET when it is missing]
cases=(
  "kitti_06_first51|$shared/data/kitti/06_first51|config/kitti.yaml|"
  "kitti_07_first160|$shared/data/kitti/07_first160|config/kitti.yaml|"
  "kitti_02_first300|$shared/data/kitti/02_first300|config/kitti.yaml|"
  "synthetic_room|$seqs/room|config/euroc.yaml|--scene room"
  "synthetic_street_turn|$seqs/street_turn|config/kitti.yaml|--scene street --path turn"
  "synthetic_street_fast|$seqs/street_fast|config/kitti.yaml|--scene street --path fast"
  "V1_01_easy_30s|$renders/V1_01_easy_30s|config/euroc.yaml|"
  "V1_03_difficult_20s|$renders/V1_03_difficult_20s|config/euroc.yaml|"
)

selected() {
  [ ${#only[@]} -eq 0 ] && return 0
  local o
  for o in "${only[@]}"; do [ "$o" = "$1" ] && return 0; done
  return 1
}

md5() { md5sum "$1" | cut -c1-32; }
poses() { grep -vc '^#' "$1" || true; }
fingerprint() { find -L "$1" -type f -printf '%P %s %T@\n' | sort | md5sum | cut -c1-32; }

echo "regression_md5: base $base_bin, new $new_bin; load $(cut -d ' ' -f 1-3 /proc/loadavg)"
printf '%-24s %6s  %-32s  %-32s  %s\n' case poses "md5 base" "md5 new" result
differ=0
for c in "${cases[@]}"; do
  IFS='|' read -r name dataset config make_args <<<"$c"
  selected "$name" || continue
  if [ ! -d "$dataset" ] && [ -n "$make_args" ]; then
    rm -rf "$dataset.tmp"
    # shellcheck disable=SC2086
    "$base_bin/vitamin_e_make_sequence" --out "$dataset.tmp" $make_args >"$work/make_$name.log" 2>&1 \
      || ve_die "vitamin_e_make_sequence failed for $name (log: $work/make_$name.log)"
    mv "$dataset.tmp" "$dataset"
  fi
  if [ ! -d "$dataset" ]; then
    printf '%-24s %6s  %-32s  %-32s  %s\n' "$name" - - - "skipped (no $dataset)"
    continue
  fi
  mkdir -p "$runs/$name"
  for side in base new; do
    bin="$base_bin" config_path="$base_configs/$(basename "$config")"
    [ "$side" = new ] && bin="$new_bin" config_path="$VE_ROOT/$config"
    [ -f "$config_path" ] || ve_die "no config $config_path"
    key="$cache/$(md5 "$bin/vitamin_e_run")_${name}_$(md5 "$config_path")_$(fingerprint "$dataset")"
    out="$runs/$name/$side"
    if [ ! -f "$key" ] || [ "$keep" = 1 ]; then
      rm -rf "$out"
      "$bin/vitamin_e_run" --dataset "$dataset" --config "$config_path" --out "$out" --quiet \
        >"$runs/$name/$side.log" 2>&1 || ve_die "vitamin_e_run ($side) failed on $name (log: $runs/$name/$side.log)"
      echo "$(md5 "$out/trajectory.txt") $(poses "$out/trajectory.txt")" >"$key"
    fi
    read -r "md5_$side" "poses_$side" <"$key"
  done
  a="$md5_base" b="$md5_new"
  result=same
  if [ "$a" != "$b" ]; then result=DIFFERENT; differ=1; fi
  printf '%-24s %6s  %-32s  %-32s  %s\n' "$name" "$poses_new" "$a" "$b" "$result"
done
[ "$keep" = 1 ] || rm -rf "$runs"
exit "$differ"
