#!/usr/bin/env bash
# The spread of one run: the accurate preset and GenZ-ICP 0.3.2, each with its voxel size moved
# by 1e-7, 1e-6 and 1e-5 of itself, up and down, beside the unmoved run (BENCHMARKS.md, "The
# narrowest wins against the runs' own spread").
#
#   bench/spread.sh DATA GT GENZ_PRESET
#
# DATA is a `kiss-odom simulate` folder or a KITTI `sequences/NN` folder, GT its ground truth.
# The preset's voxel is PRESET_VOXEL (default 0.5, `r_max / 200` at 100 m), GenZ-ICP's its
# preset's (GENZ_VOXEL, default 0.6: `outdoor` and `kitti`); GENZ_ARGS adds flags to GenZ-ICP
# (`--no-deskew` on kitti-mini, as bench/accurate.sh runs it). Prints one line per run: the
# system, the voxel, KITTI % (None on runs too short for it) and ATE m.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-target/spread}
. bench/peers.sh
genz_venv
data=$1 gt=$2 preset=$3
name=$(basename "$data")
read -r -a genz_args <<< "${GENZ_ARGS:-}"
mkdir -p "$OUT"

score() {
  "$BIN" eval "$1" "$gt" --json |
    python3 -c 'import json,sys; m=json.load(sys.stdin); print(m["kitti_t_err_pct"], m["ate_m"])'
}

for f in 1 1.0000001 0.9999999 1.000001 0.999999 1.00001 0.99999; do
  v=$(python3 -c "print(${PRESET_VOXEL:-0.5} * $f)")
  o=$OUT/$name-accurate-$v
  "$BIN" run "$data" --threads 1 --quiet --preset accurate --voxel-size "$v" --out "$o" >/dev/null
  echo "accurate $v $(score "$o/poses_kitti.txt")"
  g=$(python3 -c "print(${GENZ_VOXEL:-0.6} * $f)")
  "$GENZ/bin/python" bench/genz_run.py "$data" "$OUT/$name-genz-$g.txt" --preset "$preset" \
    --set "voxel_size=$g" "${genz_args[@]}" >/dev/null
  echo "genz-$preset $g $(score "$OUT/$name-genz-$g.txt")"
done
