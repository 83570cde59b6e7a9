#!/usr/bin/env bash
# Style check of the C++ files changed since BASE; checks only, never edits a file.
#   ./scripts/check_style.sh [BASE]
# BASE: a commit or branch; default: the merge-base of HEAD with origin/main (or main).
# Changed = differs from BASE in the working tree (committed or not), or new and untracked.
#   1. clang-format --dry-run -Werror with .clang-format
#   2. clang-tidy with .clang-tidy (naming, bugprone-*, performance-*), compile flags from
#      the build's compile_commands.json (./scripts/build.sh writes it); scripts/tidy.sh runs
#      the same checks on the whole tree
# Exit 0: clean; 1: findings (listed, with the command that fixes the format); 2: cannot check.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
cd "$VE_ROOT"

case "${1:-}" in
  -h|--help) ve_print_header; exit 0 ;;
esac
[ $# -le 1 ] || ve_die "usage: check_style.sh [BASE]"
command -v clang-format >/dev/null || ve_die "clang-format is not installed (./scripts/setup.sh installs it)"
clang_tidy=$(ve_clang_tidy)

if [ $# -eq 1 ]; then
  git rev-parse --verify --quiet "$1^{commit}" >/dev/null || ve_die "check_style.sh: '$1' is not a commit"
  base=$(git rev-parse "$1")
  base_name="$1"
else
  base=""
  for ref in origin/main main; do
    if git rev-parse --verify --quiet "$ref^{commit}" >/dev/null; then
      base=$(git merge-base HEAD "$ref") && base_name="merge-base of HEAD and $ref" && break
    fi
  done
  [ -n "$base" ] || ve_die "check_style.sh: no origin/main or main to compare with: give BASE"
fi

patterns=('*.h' '*.hpp' '*.cpp' '*.cc')
mapfile -t files < <({ git diff --name-only --diff-filter=ACMR "$base" -- "${patterns[@]}";
                       git ls-files --others --exclude-standard -- "${patterns[@]}"; } | sort -u)
echo "check_style: ${#files[@]} C++ file(s) changed since ${base:0:12} ($base_name)"
[ ${#files[@]} -gt 0 ] || { echo "check_style: OK (nothing to check)"; exit 0; }

findings=0

# 1. Format.
unformatted=()
for f in "${files[@]}"; do
  if ! out=$(clang-format --dry-run -Werror "$f" 2>&1); then
    unformatted+=("$f")
    n=$(grep -c 'error:' <<<"$out" || true)
    echo "clang-format: $f: $n place(s) differ from .clang-format, first:"
    grep -m 3 'error:' <<<"$out" | sed 's/^/    /'
  fi
done
if [ ${#unformatted[@]} -gt 0 ]; then
  findings=$((findings + ${#unformatted[@]}))
  echo "clang-format: ${#unformatted[@]} file(s) to format; see with: clang-format FILE | diff FILE -;" \
    "fix with: clang-format -i ${unformatted[*]}"
else
  echo "clang-format: OK"
fi

# 2. clang-tidy. Files in the compile database are checked with their own flags; headers and
# files it lacks borrow the flags of the nearest entry (same directory, else the first).
db_dir="$VE_WS/build"
[ -f "$db_dir/compile_commands.json" ] ||
  ve_die "no $db_dir/compile_commands.json: build first (./scripts/build.sh), then run check_style.sh again"
tidy_log=$(mktemp)
trap 'rm -f "$tidy_log"' EXIT
flags_for() {  # flags_for FILE: the compiler arguments for FILE, one per line
  /usr/bin/python3 - "$db_dir/compile_commands.json" "$VE_ROOT/$1" <<'EOF'
import json, os, shlex, sys
db, target = json.load(open(sys.argv[1])), os.path.realpath(sys.argv[2])
def path(e): return os.path.realpath(os.path.join(e["directory"], e["file"]))
def args(e): return e["arguments"] if "arguments" in e else shlex.split(e["command"])
best, score = None, -1
for e in db:
    p = path(e)
    s = len(os.path.commonpath([p, target]))
    if s > score: best, score = e, s
keep, a, out = ("-I", "-isystem", "-D", "-std", "-iquote"), args(best)[1:], []
i = 0
while i < len(a):
    x = a[i]
    if x in ("-I", "-isystem", "-D", "-iquote") and i + 1 < len(a):
        out += [x, a[i + 1]]; i += 2; continue
    if x.startswith(keep): out.append(x)
    i += 1
if target.endswith((".h", ".hpp")): out = ["-x", "c++"] + out
print("\n".join(out))
EOF
}
tidy=0
for f in "${files[@]}"; do
  mapfile -t flags < <(flags_for "$f")
  tidy_failed=0
  if ! "$clang_tidy" --quiet "$f" -- "${flags[@]}" >"$tidy_log" 2>&1; then tidy_failed=1; fi
  # Only what is in the file itself (HeaderFilterRegex in .clang-tidy is empty).
  if grep -q -E '(warning|error):' "$tidy_log"; then
    grep -E '(warning|error):' "$tidy_log" | sed "s|^$VE_ROOT/||" | sed 's/^/    /'
    n=$(grep -c -E '(warning|error):' "$tidy_log" || true)
    tidy=$((tidy + n))
    echo "clang-tidy: $f: $n finding(s)"
  elif [ "$tidy_failed" = 1 ]; then
    cat "$tidy_log" >&2
    ve_die "clang-tidy failed on $f without a diagnostic"
  fi
done
if [ "$tidy" -gt 0 ]; then
  findings=$((findings + tidy))
  echo "clang-tidy: $tidy finding(s) (checks and conventions: .clang-tidy)"
else
  echo "clang-tidy: OK"
fi

if [ "$findings" -gt 0 ]; then
  echo "check_style: FAILED ($findings finding(s) in ${#files[@]} changed file(s))"
  exit 1
fi
echo "check_style: OK (${#files[@]} file(s))"
