# Shared by the scripts: sourced, never run. Sets a clean PATH (Debian's python
# first: the pyenv interpreter on PATH here lacks catkin_pkg) and workspace paths.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
VE_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VE_WS="${VE_WS:-$VE_ROOT/.ws}"
export VE_ROOT VE_WS
ve_die() { echo "error: $*" >&2; exit 2; }
ve_info() { echo "[vitamin_e] $*" >&2; }
# Builds a benchmark (unless VE_NO_BUILD=1) and prints the path of its executable.
ve_bench_bin() {
  if [ "${VE_NO_BUILD:-0}" != 1 ]; then "$VE_ROOT/scripts/build.sh" --target "$1" >&2; fi
  local bin="$VE_WS/devel/lib/vitamin_e/$1"
  [ -x "$bin" ] || ve_die "$bin is missing: build first (./scripts/build.sh --target $1)"
  echo "$bin"
}
# True when any argument asks for help.
ve_wants_help() {
  local a
  for a in "$@"; do case "$a" in -h|--help) return 0 ;; esac; done
  return 1
}
