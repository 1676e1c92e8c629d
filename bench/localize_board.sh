#!/usr/bin/env bash
# A map of more than 1 km^2 localized in with a board's state (BENCHMARKS.md, "Localization in
# a prior map"): a generated suburban VLP-16 drive of FRAMES sweeps (about 5 km at 55-65 km/h
# for 3,000) builds the map from its ground truth at 100 m, 2 m voxels, 3 points a voxel, 50 m
# tiles; its revisit is localized in it with TINY's configuration (r_max 50 m, 2 m voxels, TINY
# capacities, f32, quantized map points) and run as odometry alone. Prints the map's line, the
# JSON line of bench/localize_score.py, and the RAM a board needs: the odometry's state bytes
# and the localizer's (summary.json's board_bytes).
#
#   bash bench/localize_board.sh [FRAMES] [SEED]       (default: 3000 7; about 4.5 GB of data)
#
# DATA: where the runs go (default target/bench/localize-board). The speed figure, after a run:
#   farm-bench --vs "sh -c 'exec kiss-odom run DATA/B --frames 0..600 TINY... --out O1'" \
#     -- sh -c "exec kiss-odom run DATA/B --frames 0..600 TINY... --map DATA/map.komap \
#     --initial-pose POSE --out O2"
# with TINY... the options of TINY below and POSE DATA/B/initial_pose.txt.
set -euo pipefail
FRAMES=${1:-3000}
SEED=${2:-7}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA=${DATA:-$ROOT/target/bench/localize-board}
BIN=${BIN:-$ROOT/target/release/kiss-odom}
[ -n "${BIN_BUILT:-}" ] || cargo build --release -q -p kiss-odom --manifest-path "$ROOT/Cargo.toml"
mkdir -p "$DATA"
VLP16=(--beams 16 --columns 1800 --fov-up 15 --fov-down -15 --max-range 100)
TINY=(--max-range 50 --set mapping.voxel_size=2 --set capacities=tiny --set runtime.scalar=f32
  --set runtime.map_storage=quantized)
for run in A B; do
  revisit=(); [ $run = B ] && revisit=(--revisit)
  [ -d "$DATA/$run" ] || "$BIN" simulate --frames "$FRAMES" --profile suburban --seed "$SEED" \
    "${VLP16[@]}" "${revisit[@]}" --out "$DATA/$run" >/dev/null
done
"$BIN" map build "$DATA/A" --poses "$DATA/A/poses.txt" --max-range 100 \
  --set mapping.voxel_size=2 --points-per-voxel 3 --out "$DATA/map.komap"
t0=$(date +%s.%N)
"$BIN" run "$DATA/B" "${TINY[@]}" --map "$DATA/map.komap" \
  --initial-pose "$(cat "$DATA/B/initial_pose.txt")" --out "$DATA/loc" --quiet --threads 1
t1=$(date +%s.%N)
"$BIN" run "$DATA/B" "${TINY[@]}" --out "$DATA/odo" --quiet --threads 1
t2=$(date +%s.%N)
python3 "$ROOT/bench/localize_score.py" board "$DATA/B/poses.txt" "$DATA/B/initial_pose.txt" \
  "$DATA/loc" "$DATA/odo" "$(echo "$t1 - $t0" | bc)" "$(echo "$t2 - $t1" | bc)"
python3 - "$DATA/loc/summary.json" <<'P'
import json, sys
s = json.load(open(sys.argv[1]))
odo, loc = s["state_bytes"], s["localization"]["board_bytes"]
print(f"board RAM: odometry {odo} B + localizer {loc} B = {odo + loc} B ({(odo + loc) / 1024:.0f} KiB)")
P
