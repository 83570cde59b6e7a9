# Shared by the scripts: sourced, never run. Sets a clean PATH (Debian's python
# first: the pyenv interpreter on PATH here lacks catkin_pkg) and workspace paths.
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
VE_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VE_WS="${VE_WS:-$VE_ROOT/.ws}"
export VE_ROOT VE_WS
ve_die() { echo "error: $*" >&2; exit 2; }
ve_info() { echo "[vitamin_e] $*" >&2; }
