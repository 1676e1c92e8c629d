#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 2, "Speed against the reference, one thread" and "Frame-time
# spread with a work budget", and section 3, "The map against the reference's" (its quantized
# map): speed against the reference (f64, exact, 1 thread, poses compared by the harness) on
# every kitti-mini sequence and a generated urban drive, the latency spread after frame 10 on
# the urban drive and a fast one, unbudgeted and budgeted, and the quantized full-scale map
# against the reference's on kitti-mini 01 and the urban drive.
#
#   KISS_ODOM_PYTHON=target/refvenv/bin/python bench/realtime.sh | tee target/bench/realtime.txt
#
# The drives go to DATA (default target/bench/realtime; made if missing). REPEATS (default 3;
# the budget table used 5) and BUDGETS (default "300000 150000 100000 50000") can be set.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom --features dev
B=target/release/kiss-odom
D=target/release/kiss-odom-dev
DATA=${DATA:-target/bench/realtime}; mkdir -p "$DATA"
U="$DATA/urban-7-200"
[ -f "$U/sim.toml" ] || $B simulate --out "$U" --frames 200 --seed 7 >/dev/null
REPEATS=${REPEATS:-3}
for s in 01 02 04 05; do
  echo "== kitti-mini $s f64 exact"
  $D bench ../shared/data/kitti-mini/sequences/$s --threads 1 --set runtime.scalar=f64 --repeats "$REPEATS" --latency-from 1
done
echo "== urban-7-200 f64 exact"
$D bench "$U" --threads 1 --set runtime.scalar=f64 --repeats "$REPEATS" --latency-from 10
# The latency spread with and without a budget (no reference: it has no budget), on the urban
# drive and a fast one. bench prints wall-clock and this thread's CPU time per frame; on a
# shared machine the CPU time is the figure other processes do not inflate.
F="$DATA/fast-5-500"
[ -f "$F/sim.toml" ] || $B simulate --out "$F" --profile fast --frames 500 --seed 5 >/dev/null
for d in "$U" "$F"; do
  for b in none ${BUDGETS:-300000 150000 100000 50000}; do
    echo "== $d f64 exact, budget $b"
    flag=(); [ "$b" = none ] || flag=(--set registration.work_budget="$b")
    $D bench "$d" --threads 1 --set runtime.scalar=f64 --repeats "$REPEATS" --latency-from 10 "${flag[@]}" --no-reference
  done
done
for d in ../shared/data/kitti-mini/sequences/01 "$U"; do
  echo "== $d f64 quantized (map bytes)"
  $D bench "$d" --threads 1 --set runtime.scalar=f64 --set runtime.map_storage=quantized --repeats 1 --latency-from 1
done
