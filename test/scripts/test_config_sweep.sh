#!/usr/bin/env bash
# Test of ./scripts/config_sweep.py with stand-in binaries (no data, seconds): each
# variant's key reaches the run's config, the table has a cell per clip and variant,
# the ratio rows compare with the first variant, --keep reuses a run made with the
# same config, and bad input stops with an error.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fails=0
expect() {  # expect DESCRIPTION EXPECTED ACTUAL
  if [ "$2" = "$3" ]; then echo "ok: $1"; else echo "FAIL: $1: expected '$2', got '$3'"; fails=$((fails + 1)); fi
}

# Stand-ins: the run's "ATE" is map.max_keyframes cm (ground.enabled true adds 1 cm); every run is logged.
mkdir -p "$tmp/bin" "$tmp/data/a" "$tmp/data/b"
cat >"$tmp/bin/vitamin_e_run" <<'RUN'
#!/usr/bin/python3
import json, os, sys, yaml
a = sys.argv
cfg = yaml.safe_load(open(a[a.index("--config") + 1]))
out = a[a.index("--out") + 1]
ate = cfg["map"]["max_keyframes"] + (1 if cfg.get("ground", {}).get("enabled") else 0)
assert cfg["dense"]["enabled"] is False
open(os.path.join(out, "trajectory.txt"), "w").write("%d\n" % ate)
late = "--start-frame" in a
json.dump({"frames": 10, "success_after_init": 0.5 if late else 1, "init_retries": 1 if late else 0,
           "relocalizations": 2 if late else 0}, open(os.path.join(out, "stats.json"), "w"))
open(os.environ["SWEEP_LOG"], "a").write(out + "\n")
RUN
cat >"$tmp/bin/vitamin_e_evaluate" <<'EVAL'
#!/usr/bin/python3
import json, sys
print(json.dumps({"ate_rmse_m": int(open(sys.argv[1]).read()) / 100.0, "ate_path_percent": 1.0}))
EVAL
chmod +x "$tmp/bin/"*
touch "$tmp/data/a/poses.txt" "$tmp/data/b/poses.txt"
printf 'map:\n  max_keyframes: 10\nground:\n  enabled: false\n' >"$tmp/base.yaml"
cat >"$tmp/clips.txt" <<CLIPS
# a comment
A $tmp/base.yaml $tmp/data/a
B $tmp/base.yaml $tmp/data/b - --start-frame 5
C $tmp/base.yaml $tmp/data/none
CLIPS
export SWEEP_LOG="$tmp/runs.log"
sweep="$root/scripts/config_sweep.py"
"$sweep" "$tmp/clips.txt" --variant base --variant k20:map.max_keyframes=20 --variant k5g:map.max_keyframes=5,ground.enabled=true \
  --bin "$tmp/bin" --out "$tmp/out" >"$tmp/table.md" 2>"$tmp/err"
expect "row A" "| A | 10.00 | 20.00 | 6.00 |" "$(grep '^| A ' "$tmp/table.md")"
expect "row B (half the frames tracked, a new map, 2 relocalizations)" "| B | 10.00 !50% i1 r2 | 20.00 !50% i1 r2 | 6.00 !50% i1 r2 |" \
  "$(grep '^| B ' "$tmp/table.md")"
expect "missing clip not in the table" "0" "$(grep -c '^| C ' "$tmp/table.md" || true)"
expect "missing clip reported" "1" "$(grep -c 'does not exist' "$tmp/err")"
expect "geometric mean" "| geometric mean ratio to base | 1.00 | 2.00 | 0.60 |" "$(grep '^| geometric' "$tmp/table.md")"
expect "six runs" "6" "$(wc -l <"$tmp/runs.log")"
"$sweep" "$tmp/clips.txt" --variant base --variant k20:map.max_keyframes=20 --bin "$tmp/bin" --out "$tmp/out" --keep \
  >/dev/null 2>&1
expect "--keep runs nothing again" "6" "$(wc -l <"$tmp/runs.log")"
"$sweep" "$tmp/clips.txt" --variant base --variant k20:map.max_keyframes=30 --bin "$tmp/bin" --out "$tmp/out" --keep \
  >"$tmp/table2.md" 2>/dev/null
expect "--keep runs a changed config" "| A | 10.00 | 30.00 |" "$(grep '^| A ' "$tmp/table2.md")"

bad() {  # bad DESCRIPTION ARGS...: exit code != 0 and an error: line
  local desc="$1"; shift
  if "$sweep" "$@" >"$tmp/o" 2>"$tmp/e"; then echo "FAIL: $desc: exit code 0"; fails=$((fails + 1)); return; fi
  if grep -q '^error: ' "$tmp/e"; then echo "ok: $desc"; else echo "FAIL: $desc:"; cat "$tmp/e"; fails=$((fails + 1)); fi
}
bad "no such binary folder" "$tmp/clips.txt" --variant base --bin "$tmp/none"
bad "a change without a section" "$tmp/clips.txt" --variant x:max_keyframes=3 --bin "$tmp/bin"
bad "a short clip line" <(echo "A $tmp/base.yaml") --variant base --bin "$tmp/bin"

[ "$fails" = 0 ] || { echo "$fails check(s) failed"; exit 1; }
echo "all checks passed"
