#!/usr/bin/env bash
# Reproduces the spread noted under BENCHMARKS.md section 15, "Against kiss-icp, GenZ-ICP and
# MAD-ICP": the spread of one run, the accurate preset and GenZ-ICP 0.3.2 each with its voxel
# size moved by 1e-7, 1e-6 and 1e-5 of itself, up and down, beside the unmoved run.
#
#   bench/spread.sh DATA GENZ_PRESET
#   bash bench/spread.sh target/bench/accurate/urban-500-s1 outdoor   (a drive bench/accurate.sh made)
#
# DATA is a `kiss-odom simulate` folder or a KITTI `sequences/NN` folder (its ground truth is
# the one `kiss-odom run` finds). The preset's voxel is PRESET_VOXEL (default 0.5, `r_max / 200`
# at 100 m), GenZ-ICP's its preset's (GENZ_VOXEL, default 0.6: `outdoor` and `kitti`);
# GENZ_ARGS adds flags to GenZ-ICP (`--no-deskew` on kitti-mini, as bench/accurate.sh runs it).
# Each run is run and scored as bench/accurate.sh does it (bench/peers.sh), into
# $OUT/results.jsonl; prints one line per run: the system, the factor on its voxel, KITTI %
# (None on runs too short for it) and ATE m.
set -euo pipefail
cd "$(dirname "$0")/.."
data=$1 preset=$2
name=$(basename "$data")
OUT=${OUT:-target/bench/spread/$name}
. bench/peers.sh
genz_venv
read -r -a genz_args <<< "${GENZ_ARGS:-}"
mkdir -p "$OUT"
: > "$OUT/results.jsonl"

for f in 1 1.0000001 0.9999999 1.000001 0.999999 1.00001 0.99999; do
  v=$(python3 -c "print(${PRESET_VOXEL:-0.5} * $f)")
  g=$(python3 -c "print(${GENZ_VOXEL:-0.6} * $f)")
  gt=$(ours "$f" "$data" accurate --preset accurate --set "mapping.voxel_size=$v")
  genz "$f" "$data" "$preset" "$gt" --set "voxel_size=$g" "${genz_args[@]}"
done
python3 -c '
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    print(r["system"], r["run"], r["kitti_t_err_pct"], r["ate_m"])
' "$OUT/results.jsonl"
