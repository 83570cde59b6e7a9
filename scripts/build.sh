#!/usr/bin/env bash
# Builds vitamin_e in a catkin workspace at .ws/ (git-ignored; src/vitamin_e links
# to this repository's files). Installs missing Debian packages first.
#   ./scripts/build.sh [--sanitize] [--tests] [--target T ...]
# --sanitize builds with ASan+UBSan in .ws_sanitize/ instead.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
ve_help_on_request "$@"

sanitize=OFF
tests=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize) sanitize=ON; VE_WS="$VE_ROOT/.ws_sanitize" ;;
    --tests) tests=1 ;;
    --target) shift; targets+=("$1") ;;
    *) ve_die "build.sh: unknown option '$1'" ;;
  esac
  shift
done
export VE_WS

"$VE_ROOT/scripts/setup.sh"

mkdir -p "$VE_WS/src"
# The workspace's package folder holds a link to each entry of the checkout, not a link to
# the checkout itself: the checkout holds the workspace, and rospack and rosrun (find -L)
# would walk into it again ("File system loop detected", executables found twice, in
# build/, devel/ and install/).
pkg="$VE_WS/src/vitamin_e"
[ -L "$pkg" ] && rm "$pkg"
mkdir -p "$pkg"
ws_real="$(cd -P "$VE_WS" && pwd)"
for entry in "$VE_ROOT"/*; do
  entry_real="$(cd -P "$(dirname "$entry")" && pwd)/$(basename "$entry")"
  case "$ws_real/" in "$entry_real"/*) continue ;; esac  # the workspace (or what holds it)
  link="$pkg/$(basename "$entry")"
  [ -e "$link" ] || [ -L "$link" ] || ln -s "$entry" "$link"
done
for link in "$pkg"/*; do
  if [ -L "$link" ] && [ ! -e "$link" ]; then rm "$link"; fi  # an entry removed from the checkout
done
if [ ! -e "$VE_WS/src/CMakeLists.txt" ]; then
  ln -s /usr/share/catkin/cmake/toplevel.cmake "$VE_WS/src/CMakeLists.txt"
fi

jobs="${VE_JOBS:-$(nproc)}"
build_type="Release"
[ "$sanitize" = ON ] && build_type="RelWithDebInfo"
if [ ! -f "$VE_WS/build/Makefile" ] || [ ! -f "$VE_WS/build/.ve_configured_$sanitize" ]; then
  rm -rf "$VE_WS/build"
  mkdir -p "$VE_WS/build"
  launcher=()
  # ccache (setup.sh installs it) makes rebuilds cheap, and with the checkout as its base
  # directory (paths under it hashed as relative ones) a second checkout's or a fresh clone's
  # build of the same sources too.
  if command -v ccache >/dev/null 2>&1; then
    cc_launcher="/usr/bin/env;CCACHE_BASEDIR=$VE_ROOT;ccache"
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$cc_launcher" -DCMAKE_C_COMPILER_LAUNCHER="$cc_launcher")
  fi
  (cd "$VE_WS/build" && cmake ../src "${launcher[@]}" \
      -DCMAKE_BUILD_TYPE="$build_type" \
      -DCATKIN_DEVEL_PREFIX="$VE_WS/devel" \
      -DCMAKE_INSTALL_PREFIX="$VE_WS/install" \
      -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
      -DVITAMIN_E_SANITIZE="$sanitize" -DCATKIN_ENABLE_TESTING=ON >"$VE_WS/configure.log" 2>&1) \
    || { tail -40 "$VE_WS/configure.log" >&2; rm -rf "$VE_WS/build"; ve_die "cmake configure failed (log: $VE_WS/configure.log)"; }
  touch "$VE_WS/build/.ve_configured_$sanitize"
fi

# Re-glob sources (new files in src/<module>/, tests, benchmarks) before naming targets.
make -C "$VE_WS/build" --no-print-directory cmake_check_build_system >/dev/null 2>&1 || true
# Compiler output goes to $VE_WS/build.log (shown on failure); VE_VERBOSE=1 shows it live.
log="$VE_WS/build.log"
run_make() {
  if [ "${VE_VERBOSE:-0}" = 1 ]; then
    make -C "$VE_WS/build" -j"$jobs" --no-print-directory "$@"
  else
    make -C "$VE_WS/build" -j"$jobs" --no-print-directory "$@" >>"$log" 2>&1 \
      || { grep -E "error|Error" "$log" | head -40 >&2; ve_die "build failed (full log: $log)"; }
  fi
}
: >"$log"
if [ ${#targets[@]} -gt 0 ]; then
  for t in "${targets[@]}"; do
    run_make "$t"
  done
else
  ve_info "building (log: $log)"
  run_make
  if [ "$tests" = 1 ]; then
    run_make tests
  fi
fi
