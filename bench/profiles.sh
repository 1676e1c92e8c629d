#!/usr/bin/env bash
# Accuracy of `kiss-odom run` on each simulator profile, deskew on and off (BENCHMARKS.md,
# "Simulator profiles"). Prints one Markdown row per profile and setting.
#
#   bench/profiles.sh [FRAMES]     (default 200; datasets go to $GEN/profile-<name>)
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-200}
GEN=${GEN:-/work/data-gen}
cargo build --release -q -p kiss-odom
BIN=${CARGO_TARGET_DIR:-target}/release/kiss-odom
row() {
  python3 - "$1" "$2" "$3" <<'PY'
import json, sys
name, mode, path = sys.argv[1:]
s = json.load(open(path))
m = s.get("metrics", {})
flags = s.get("degraded_frames", {})
def f(k, fmt="{:.3f}"):
    return fmt.format(m[k]) if k in m and m[k] is not None else "n/a"
print(f"| {name} | {mode} | {s['frames']} | {f('ate_m')} | {f('final_error_m')} | "
      f"{f('rpe_m_mean', '{:.4f}')} | {f('kitti_t_err_pct', '{:.2f}')} | "
      f"{', '.join(f'{k} {v}' for k, v in flags.items()) or '-'} |")
PY
}
echo "| profile | deskew | frames | ATE m | final error m | RPE mean m | KITTI t_err % | flagged frames |"
echo "|---|---|---|---|---|---|---|---|"
for p in urban fast corridor plane; do
  d=$GEN/profile-$p-$FRAMES
  [ -f "$d/poses.txt" ] || "$BIN" simulate --out "$d" --frames "$FRAMES" --seed 3 --profile "$p" >/dev/null
  for mode in deskew no-deskew; do
    o=$GEN/profile-runs/$p-$FRAMES-$mode
    "$BIN" run "$d" --"$mode" --threads 1 --quiet --out "$o" >/dev/null
    row "$p" "$mode" "$o/summary.json"
  done
done
