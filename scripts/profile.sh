#!/usr/bin/env bash
# Where the instructions go: vitamin_e_run (sequential, dense on) under valgrind's callgrind on the
# first frames of a dataset. Instruction counts do not depend on the machine's load (wall-clock
# times on a shared machine do), so two builds or two commits compare exactly.
#   ./scripts/profile.sh DATASET [--config YAML] [--frames N] [--stride N] [--bin DIR] [--out DIR] [--top N]
# Prints the instructions per frame of each stage (inclusive: a stage's functions and all they
# call) and the top N functions by their own instructions; the callgrind file stays in OUT for
# callgrind_annotate / kcachegrind. OpenCV's parallel loops run on the calling thread
# (OPENCV_FOR_THREADS_NUM=1) so that the tracker's stripes count under the tracker.
# Default: 40 frames, config/euroc.yaml (config/kitti.yaml for a KITTI folder), this build.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
usage="usage: ./scripts/profile.sh DATASET [--config YAML] [--frames N] [--stride N] [--bin DIR] [--out DIR] [--top N]"
ve_help_on_request "$@"
[ $# -ge 1 ] || ve_die "$usage"
dataset="$1"; shift
config="" frames=40 stride=1 bin="" top=25
out="$(mktemp -d /tmp/ve_profile.XXXXXX)"
while [ $# -gt 0 ]; do
  case "$1" in
    --config|--frames|--stride|--bin|--out|--top) [ $# -ge 2 ] || ve_die "$1 needs a value ($usage)" ;;&
    --config) config="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --stride) stride="$2"; shift 2 ;;
    --bin) bin="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --top) top="$2"; shift 2 ;;
    *) ve_die "unknown option '$1' ($usage)" ;;
  esac
done
[ -e "$dataset" ] || ve_die "dataset '$dataset' does not exist"
[[ "$frames" =~ ^[1-9][0-9]*$ ]] || ve_die "--frames must be a positive integer, got '$frames'"
command -v valgrind >/dev/null && command -v callgrind_annotate >/dev/null \
  || ve_die "valgrind is not installed (apt-get install valgrind)"
if [ -z "$config" ]; then
  config="$VE_ROOT/config/euroc.yaml"
  # A KITTI odometry folder (as vitamin_e::io::detectDatasetKind tells it).
  if [ -f "$dataset/calib.txt" ] && { [ -d "$dataset/image_0" ] || [ -d "$dataset/image_l" ]; }; then
    config="$VE_ROOT/config/kitti.yaml"
  fi
fi
if [ -z "$bin" ]; then
  bin="$VE_WS/devel/lib/vitamin_e"
  if [ "${VE_NO_BUILD:-0}" != 1 ]; then "$VE_ROOT/scripts/build.sh" --target vitamin_e_run >&2; fi
fi
[ -x "$bin/vitamin_e_run" ] || ve_die "$bin/vitamin_e_run is missing"
mkdir -p "$out"

ve_info "callgrind: $frames frames of $dataset ($(basename "$config")), $bin; about a minute per 10 frames"
OPENCV_FOR_THREADS_NUM=1 valgrind --tool=callgrind --callgrind-out-file="$out/callgrind.out" \
  "$bin/vitamin_e_run" --dataset "$dataset" --config "$config" --out "$out/run" --quiet \
  --max-frames "$frames" --stride "$stride" >"$out/valgrind.log" 2>&1 \
  || { tail -20 "$out/valgrind.log" >&2; ve_die "the profiled run failed (log: $out/valgrind.log)"; }
callgrind_annotate --inclusive=yes "$out/callgrind.out" >"$out/inclusive.txt" 2>/dev/null
callgrind_annotate "$out/callgrind.out" >"$out/self.txt" 2>/dev/null

/usr/bin/python3 - "$out" "$frames" "$top" <<'EOF'
import json, re, sys
out, frames, top = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
# Stage -> the function whose inclusive count is the stage (first match in the listing).
STAGES = [
    ("image_load", r"vitamin_e::io::detail::(FolderDataset::loadImage|readGray)\("),
    ("tracking", r"vitamin_e::pipeline::FrontEnd::track\("),
    ("  curvature", r"vitamin_e::tracking::computeCurvature\("),
    ("  flow (BRIEF + affine)", r"vitamin_e::tracking::extractSmallFeatures\("),
    ("  climb", r"vitamin_e::tracking::DenseTracker::Impl::trackAll\("),
    ("  patch align", r"vitamin_e::tracking::DenseTracker::Impl::alignSteps\("),
    ("  detect", r"vitamin_e::tracking::DenseTracker::Impl::detect\("),
    ("mapping", r"vitamin_e::pipeline::System::Impl::mapFrame\("),
    ("  pose (P3P RANSAC)", r"vitamin_e::geometry::solvePnpRansac\("),
    ("  BA (frame + window)", r"vitamin_e::optimization::solveSubspaceGaussNewton\("),
    ("  keyframe", r"vitamin_e::pipeline::Mapper::addKeyframe\("),
    ("  triangulation", r"vitamin_e::pipeline::Mapper::triangulate\("),
    ("  map reuse", r"vitamin_e::pipeline::MapReuse::associate\("),
    ("  relocalizer keyframe", r"vitamin_e::pipeline::Relocalizer::addKeyframe\("),
    ("  backlog diagnostic", r"vitamin_e::pipeline::Mapper::backlog\("),
    ("mesh (Delaunay + NLTGV)", r"vitamin_e::fusion::DenseMapper::addFrame\("),
    ("  Delaunay mesh", r"vitamin_e::meshing::FrameMesher::buildFromPoints\("),
    ("  NLTGV", r"vitamin_e::meshing::NltgvDenoiser::denoise\("),
    ("tsdf", r"vitamin_e::fusion::TsdfVolume::integrate\("),
]
# "  1,234 (12.3%)  file.cpp:ns::function(args) [object]": the file never holds "::".
line_re = re.compile(r"^\s*([\d,]+)\s+\(\s*[\d.]+%\)\s+(?:[^:\s]*:(?!:))?(.*)$")
def parse(path):
    rows = []
    total = 0
    for line in open(path):
        if "PROGRAM TOTALS" in line:
            total = int(line.split()[0].replace(",", ""))
            continue
        m = line_re.match(line)
        if m:
            rows.append((int(m.group(1).replace(",", "")), m.group(2).strip()))
    return total, rows
total, incl = parse(f"{out}/inclusive.txt")
_, self_rows = parse(f"{out}/self.txt")
print(f"callgrind, {frames} frames: {total / 1e6:.0f} M instructions in all, {total / frames / 1e6:.1f} M per frame")
print(f"{'stage':28} {'M instr/frame':>14} {'% of all':>9}")
res = {"frames": frames, "total_minstr": total / 1e6, "stages": {}, "top_self": []}
for name, pat in STAGES:
    r = re.compile(pat)
    hit = next((c for c, fn in incl if r.search(fn)), None)
    if hit is None:
        continue
    res["stages"][name.strip()] = hit / frames / 1e6
    print(f"{name:28} {hit / frames / 1e6:14.2f} {100.0 * hit / total:8.1f}%")
print(f"\ntop {top} functions by own instructions:")
for c, fn in self_rows[:top]:
    short = re.sub(r"\(.*", "", fn)[:100]
    print(f"{100.0 * c / total:6.2f}%  {c / frames / 1e6:8.2f} M/frame  {short}")
    res["top_self"].append({"function": short, "percent": 100.0 * c / total})
print(f"(files: {out}/callgrind.out, inclusive.txt, self.txt)")
print(json.dumps(res))
EOF
