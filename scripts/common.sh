# Shared by the scripts: sourced, never run. Sets a clean PATH (Debian's python
# first: the pyenv interpreter on PATH here lacks catkin_pkg) and workspace paths.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
# -P: the checkout itself, also when a script is run through the workspace's links to it.
VE_ROOT="$(cd -P "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VE_WS="${VE_WS:-$VE_ROOT/.ws}"
export VE_ROOT VE_WS
ve_die() { echo "error: $*" >&2; exit 2; }
# ve_ros_env: the built workspace's ROS environment, loopback only, logs inside the workspace
# (unless ROS_HOME / ROS_LOG_DIR are set). Call it without arguments: setup.bash reads them.
ve_ros_env() {
  local had_u=0
  case $- in *u*) had_u=1 ;; esac
  set +u
  source "$VE_WS/devel/setup.bash"
  [ "$had_u" = 0 ] || set -u
  export ROS_IP=127.0.0.1 ROS_HOSTNAME=localhost
  unset ROS_IPV6
  export ROS_HOME="${ROS_HOME:-$VE_WS/ros_home}"
  export ROS_LOG_DIR="${ROS_LOG_DIR:-$ROS_HOME/log}"
  mkdir -p "$ROS_LOG_DIR"
}
ve_info() { echo "[vitamin_e] $*" >&2; }
# ve_list_path P: a path of a suite list as an absolute path: ../shared/... under VE_SHARED,
# ../renders/... under VE_RENDERS, other relative paths from the repository root ("" stays "").
ve_list_path() {
  case "$1" in
    /*|"") echo "$1" ;;
    ../shared/*) echo "${VE_SHARED:-$VE_ROOT/../shared}/${1#../shared/}" ;;
    ../renders/*) echo "${VE_RENDERS:-$VE_ROOT/../renders}/${1#../renders/}" ;;
    *) echo "$VE_ROOT/$1" ;;
  esac
}
# Builds a benchmark (unless VE_NO_BUILD=1) and prints the path of its executable.
ve_bench_bin() {
  if [ "${VE_NO_BUILD:-0}" != 1 ]; then "$VE_ROOT/scripts/build.sh" --target "$1" >&2; fi
  local bin="$VE_WS/devel/lib/vitamin_e/$1"
  [ -x "$bin" ] || ve_die "$bin is missing: build first (./scripts/build.sh --target $1)"
  echo "$bin"
}
# ve_clang_tidy: the one clang-tidy the style checks use (scripts/setup.sh installs it); its
# checks differ from version to version, so CI and developers must run the same one.
ve_clang_tidy() {
  command -v clang-tidy-22 || ve_die "clang-tidy-22 is not installed (./scripts/setup.sh installs it)"
}
# True when any argument asks for help.
ve_wants_help() {
  local a
  for a in "$@"; do case "$a" in -h|--help) return 0 ;; esac; done
  return 1
}
# The calling script's header comment (the lines after the shebang that start with '#'): its usage.
ve_print_header() {
  awk 'NR == 1 && /^#!/ { next } /^#/ { sub(/^# ?/, ""); print; next } { exit }' "$0"
}
# With -h or --help among the script's own arguments (those before a '--', which may be passed
# on to another tool), prints the header and exits 0; a script calls it before it acts.
ve_help_on_request() {
  local a
  for a in "$@"; do
    case "$a" in
      --) return 0 ;;
      -h|--help) ve_print_header; exit 0 ;;
    esac
  done
}
# Provenance of an evaluation run, read by ./scripts/results.sh: OUT/run_info.txt gets the
# command (with the data roots), commit, machine, start time and load; ..._end adds the end.
#   ve_suite_info_begin OUT COMMAND ARGS...    ve_suite_info_end OUT
ve_suite_info_begin() {
  local out="$1"; shift
  # What the results depend on (an edited README does not change them).
  local ve_result_paths="src include cmake CMakeLists.txt package.xml config scripts bench"
  {
    printf 'command:'
    [ -n "${VE_SHARED:-}" ] && printf ' VE_SHARED=%q' "$VE_SHARED"
    [ -n "${VE_RENDERS:-}" ] && printf ' VE_RENDERS=%q' "$VE_RENDERS"
    printf ' %q' "$@"
    echo
    echo "commit: $(git -C "$VE_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)$(
      [ -n "$(git -C "$VE_ROOT" status --porcelain --untracked-files=no -- $ve_result_paths 2>/dev/null)" ] \
        && echo ' (with uncommitted changes)')"
    echo "cpu: $(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)"
    echo "cores: $(nproc)"
    echo "memory_gb: $(awk '/^MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
    echo "os: $(. /etc/os-release 2>/dev/null && echo "${PRETTY_NAME:-unknown}")"
    echo "started: $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "load_start: $(cut -d ' ' -f 1-3 /proc/loadavg)"
  } >"$out/run_info.txt"
}
ve_suite_info_end() {
  {
    echo "finished: $(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "load_end: $(cut -d ' ' -f 1-3 /proc/loadavg)"
  } >>"$1/run_info.txt"
}
