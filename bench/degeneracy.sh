#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 12, "Robust mode against the reference and GenZ-ICP":
# kiss-odom reference mode, robust mode and GenZ-ICP 0.3.2 on the same generated runs and on
# kitti-mini.
#
#   nice bash bench/degeneracy.sh [FRAMES] [SEEDS]     (default 500 frames, seeds "1 2 3"; about
#                                                       an hour on 2 shared cores)
#
# PROFILES picks the runs (default "corridor plane tunnel field urban fast kitti"; `kitti` is
# every kitti-mini sequence). GenZ-ICP runs its `corridor` preset on corridor, plane and tunnel,
# `outdoor` on field, urban and fast, `kitti` (no deskew) on kitti-mini; robust mode runs with
# its vehicle prior everywhere (--set registration.lateral_prior=1: every run is a car's) and its tunnel setting
# where GenZ-ICP has its corridor preset: every frame with plane terms, r_max / 200 voxels and
# the hold prior (--set registration.plane_gate=1 --set mapping.voxel_size=0.5 --set registration.prediction_prior=0.01).
#
# The drives are generated into $GEN (default target/bench/degeneracy; kept for reruns).
# Writes $OUT/results.jsonl (one line per run and system, with the estimated over the true
# distance travelled) and prints the Markdown table
# (bench/degeneracy_table.py). GenZ-ICP runs from a venv made here (target/genzvenv).
# Every system runs on one thread; run it alone at `nice` on a shared machine. REUSE_PEERS=1
# re-runs only kiss-odom, keeping GenZ-ICP's poses of an earlier run in the same $OUT.
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-500}
SEEDS=${2:-"1 2 3"}
PROFILES=${PROFILES:-"corridor plane tunnel field urban fast kitti"}
GEN=${GEN:-target/bench/degeneracy}
OUT=${OUT:-$GEN/results-$FRAMES}
. bench/peers.sh
genz_venv
mkdir -p "$OUT"
: > "$OUT/results.jsonl"

for p in $PROFILES; do
  case $p in
    kitti) continue ;;
    corridor | plane | tunnel)
      preset=corridor fine=(--set registration.lateral_prior=1 --set registration.plane_gate=1 --set mapping.voxel_size=0.5 --set registration.prediction_prior=0.01) ;;
    *) preset=outdoor fine=(--set registration.lateral_prior=1) ;;
  esac
  for s in $SEEDS; do
    d=$GEN/$p-$FRAMES-s$s
    [ -f "$d/poses.txt" ] || "$BIN" simulate --out "$d" --frames "$FRAMES" --seed "$s" --profile "$p" >/dev/null
    name=$p-s$s
    echo "== $name" >&2
    ours "$name" "$d" reference --set registration.degeneracy=reference >/dev/null
    ours "$name" "$d" robust --set registration.degeneracy=robust "${fine[@]}" >/dev/null
    genz "$name" "$d" "$preset" "$d/poses.txt"
  done
done
for sq in $( [[ " $PROFILES " == *" kitti "* ]] && ls "$KITTI/sequences"); do
  d=$KITTI/sequences/$sq
  name=kitti-$sq
  echo "== $name" >&2
  gt=$(ours "$name" "$d" reference --set registration.degeneracy=reference)
  ours "$name" "$d" robust --set registration.degeneracy=robust --set registration.lateral_prior=1 >/dev/null
  genz "$name" "$d" kitti "$gt" --no-deskew
done
python3 bench/degeneracy_table.py "$OUT/results.jsonl"
