#!/usr/bin/env bash
# SLAM time per frame of two builds side by side: vitamin_e_run of BIN_A and of
# BIN_B on the same dataset, alternately (A B A B ...), so that both see the
# same machine load. Per run: the mean and median of the per-frame time
# (stats.json timing_ms.total: tracking + mapping, wall clock) and the process
# CPU time (user + sys, steadier than wall clock on a loaded machine).
#   ./scripts/bench_compare.sh BIN_A BIN_B DATASET [--runs N] [--out DIR] [-- vitamin_e_run options]
# BIN_A/BIN_B: directories holding vitamin_e_run (e.g. .ws/devel/lib/vitamin_e
# of two worktrees). Without a --config after --, config/euroc.yaml is used.
# Last line: JSON with the means over the runs and the ratios B/A.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
usage="usage: ./scripts/bench_compare.sh BIN_A BIN_B DATASET [--runs N] [--out DIR] [-- vitamin_e_run options]"
if ve_wants_help "${@:1:3}"; then echo "$usage"; exit 0; fi
[ $# -ge 3 ] || ve_die "$usage"
bin_a="$1" bin_b="$2" dataset="$3"
shift 3
runs=3
out="$(mktemp -d /tmp/ve_bench_compare.XXXXXX)"
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) [ $# -ge 2 ] || ve_die "--runs needs a value"; runs="$2"; shift 2 ;;
    --out) [ $# -ge 2 ] || ve_die "--out needs a value"; out="$2"; shift 2 ;;
    --) shift; break ;;
    *) ve_die "unknown option '$1' ($usage)" ;;
  esac
done
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || ve_die "--runs must be a positive integer, got '$runs'"
for b in "$bin_a" "$bin_b"; do [ -x "$b/vitamin_e_run" ] || ve_die "$b/vitamin_e_run is missing"; done
[ -e "$dataset" ] || ve_die "dataset '$dataset' does not exist"
extra=("$@")
has_config=0
for a in "${extra[@]}"; do [ "$a" = --config ] && has_config=1; done
[ "$has_config" = 1 ] || extra+=(--config "$VE_ROOT/config/euroc.yaml")
mkdir -p "$out"

ve_info "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for ((i = 1; i <= runs; ++i)); do
  for side in a b; do
    bin="$bin_a"; [ "$side" = b ] && bin="$bin_b"
    dir="$out/$side$i"
    /usr/bin/time -f "%U %S" -o "$dir.cpu" "$bin/vitamin_e_run" --dataset "$dataset" --out "$dir" --quiet \
      "${extra[@]}" >/dev/null 2>"$dir.stderr" || { cat "$dir.stderr" >&2; ve_die "run $side$i failed"; }
  done
done
ve_info "load after: $(cut -d' ' -f1-3 /proc/loadavg)"

/usr/bin/python3 - "$out" "$runs" <<'EOF'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
res = {}
for side in "ab":
    mean, median, cpu = [], [], []
    for i in range(1, runs + 1):
        t = json.load(open(f"{out}/{side}{i}/stats.json"))["timing_ms"]["total"]
        u, s = map(float, open(f"{out}/{side}{i}.cpu").read().split()[-2:])
        mean.append(t["mean"]); median.append(t["median"]); cpu.append(u + s)
        print(f"{side}{i}: per-frame total mean {t['mean']:.2f} ms, median {t['median']:.2f} ms, "
              f"{t['count']} frames, process CPU {u + s:.2f} s")
    res[side] = {"total_mean_ms": statistics.mean(mean), "total_median_ms": statistics.mean(median),
                 "cpu_s": statistics.mean(cpu)}
res["ratio_b_a"] = {k: res["b"][k] / res["a"][k] for k in res["a"]}
res["runs"] = runs
print(json.dumps(res))
EOF
