#!/usr/bin/env bash
# Reproduces BENCHMARKS.md's "Every rule on real data": the preset, the
# preset with each rule off in turn and the default on the real recordings with ground truth
# or a reference trajectory (cells: ATE m / mean RPE m / frames/s in the core).
#
#   bash bench/ablation.sh                      # ../shared/data's kitti-mini
#   REAL=/path/to/real bash bench/ablation.sh   # and every folder of REAL (generic layout with
#                                               # poses.txt: see BENCHMARKS.md for the public
#                                               # recordings used and where they come from)
#   GENERATED=1 bash bench/ablation.sh          # and the generated profiles (200 frames, seed 61)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
OUT=${OUT:-target/bench/ablation}
K=../shared/data/kitti-mini/sequences
sets=("kitti-mini/kitti-01=$K/01" "kitti-mini/kitti-02=$K/02" "kitti-mini/kitti-04=$K/04"
  "kitti-mini/kitti-05=$K/05")
if [ -n "${REAL:-}" ]; then
  for d in "$REAL"/*/; do
    [ -f "$d/poses.txt" ] && sets+=("real/$(basename "$d")=${d%/}")
  done
fi
if [ -n "${GENERATED:-}" ]; then
  for p in urban fast corridor tunnel field handheld drone; do
    g=$OUT/gen/$p-200-s61
    [ -f "$g/poses.txt" ] || $B simulate --profile $p --frames 200 --seed 61 --out "$g" \
      --overwrite >/dev/null
    sets+=("generated/$p=$g")
  done
  g=$OUT/gen/suburban-vlp16-200-s61
  [ -f "$g/poses.txt" ] || $B simulate --profile suburban --sensor vlp16 --frames 200 \
    --seed 61 --out "$g" --overwrite >/dev/null
  sets+=("generated/suburban-vlp16=$g")
fi
python3 bench/ablation.py $B "$OUT/runs" "${sets[@]}"
