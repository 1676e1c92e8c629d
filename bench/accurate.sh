#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 15, "Against kiss-icp, GenZ-ICP and MAD-ICP": the
# `accurate` preset against kiss-icp 1.3.0 (our default mode: its poses, bit for bit), GenZ-ICP
# 0.3.2 and MAD-ICP 0.0.10 on the same frames. Also how the preset's candidates were compared
# (ACCURATE_ARGS="--config CANDIDATE.toml" on the tuning seeds "7 8"; that section's "Tried and
# dropped").
#
#   nice bash bench/accurate.sh [FRAMES] [SEEDS]     (default 500 frames, seeds "1 2 3"; hours)
#
# PROFILES picks the runs (default "urban fast corridor tunnel field vlp16 mid360 kitti"):
# `vlp16` and `mid360` are the urban scene seen by a generated VLP-16 and Livox Mid-360
# (16 rings; a non-repetitive pattern); `kitti` is every kitti-mini sequence. GenZ-ICP gets the
# preset it has for the scene (`corridor` on corridor and tunnel, `kitti` without deskew on
# kitti-mini, `outdoor` elsewhere), MAD-ICP its defaults (`kitti` reader on kitti-mini).
# ACCURATE_ARGS adds flags to the preset's runs (to measure a candidate setting).
#
# The preset also runs in f32 (`accuratef32`), for its error against f64's (F32=0: not).
#
# The drives are generated into $GEN (default target/bench/accurate; kept for reruns).
# Writes $OUT/results.jsonl (one line per run and system) and prints the Markdown table
# (bench/accurate_table.py). Every system runs on one thread; run it alone at `nice` on a
# shared machine. The peers' venvs are made here (target/genzvenv, target/madvenv; MAD-ICP is
# built from its sdist, a few minutes). REUSE_PEERS=1 keeps the peers' poses of an earlier run
# in the same $OUT (they do not depend on kiss-odom); PEERS=0 records only such kept runs.
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-500}
SEEDS=${2:-"1 2 3"}
PROFILES=${PROFILES:-"urban fast corridor tunnel field vlp16 mid360 kitti"}
GEN=${GEN:-target/bench/accurate}
OUT=${OUT:-$GEN/results-$FRAMES}
read -r -a extra <<< "${ACCURATE_ARGS:-}"
. bench/peers.sh
if [ "${PEERS:-1}" != 0 ]; then
  genz_venv
  mad_venv
fi
mkdir -p "$OUT"
: > "$OUT/results.jsonl"

for p in $PROFILES; do
  case $p in
    kitti) continue ;;
    corridor | tunnel) profile=$p preset=corridor sim=() ;;
    vlp16 | mid360) profile=urban preset=outdoor sim=(--sensor "$p") ;;
    *) profile=$p preset=outdoor sim=() ;;
  esac
  for s in $SEEDS; do
    d=$GEN/$p-$FRAMES-s$s
    [ -f "$d/poses.txt" ] ||
      "$BIN" simulate --out "$d" --frames "$FRAMES" --seed "$s" --profile "$profile" "${sim[@]}" >/dev/null
    name=$p-s$s
    echo "== $name" >&2
    ours "$name" "$d" default >/dev/null
    ours "$name" "$d" accurate --preset accurate "${extra[@]}" >/dev/null
    [ "${F32:-1}" = 0 ] || ours "$name" "$d" accuratef32 --preset accurate --set runtime.scalar=f32 "${extra[@]}" >/dev/null
    genz "$name" "$d" "$preset" "$d/poses.txt"
    mad "$name" "$d" "$d/poses.txt"
  done
done
for sq in $( [[ " $PROFILES " == *" kitti "* ]] && ls "$KITTI/sequences"); do
  d=$KITTI/sequences/$sq
  name=kitti-$sq
  echo "== $name" >&2
  gt=$(ours "$name" "$d" default)
  ours "$name" "$d" accurate --preset accurate "${extra[@]}" >/dev/null
  [ "${F32:-1}" = 0 ] || ours "$name" "$d" accuratef32 --preset accurate --set runtime.scalar=f32 "${extra[@]}" >/dev/null
  genz "$name" "$d" kitti "$gt" --no-deskew
  mad "$name" "$d" "$gt" --kitti
done
python3 bench/accurate_table.py "$OUT/results.jsonl"
