#!/usr/bin/env bash
# Re-runs every measurement behind the speed, memory and voxel-table sections of BENCHMARKS.md.
#
#   bench/run_all.sh                  # everything (about 40 min on 2 shared cores)
#   STEPS="speed" bench/run_all.sh    # a subset: speed rss small tables stages profile
#
# Results go to $OUT (JSON and text per measurement); bench/summarize.py turns them into the
# tables of BENCHMARKS.md. Generated datasets go to $GEN and are made once. The reference
# kiss-icp 1.3.0 runs from $KISS_ODOM_PYTHON (a venv made from tests/reference/requirements.txt).
set -euo pipefail
cd "$(dirname "$0")/.."

export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-/work/targets/bench}
export KISS_ODOM_PYTHON=${KISS_ODOM_PYTHON:-/work/refvenv/bin/python}
KITTI=${KISS_ODOM_KITTI_MINI:-../shared/data/kitti-mini}
GEN=${GEN:-/work/data-gen}
OUT=${OUT:-$GEN/bench-results}
STEPS=${STEPS:-"speed rss small tables stages"}
# Timed runs per implementation and configuration (each after one untimed warm-up run).
REPEATS_KITTI=${REPEATS_KITTI:-5}
REPEATS_SIM=${REPEATS_SIM:-3}

has() { [[ " $STEPS " == *" $1 "* ]]; }
log() { printf '\n=== %s\n' "$*"; }

cargo build --release -p kiss-odom
BIN=$CARGO_TARGET_DIR/release/kiss-odom
mkdir -p "$OUT" "$GEN"

# The generated sequences (the simulator's bytes depend on the seed and flags only).
for n in 500 2000; do
  if [ ! -f "$GEN/urban-$n/poses.txt" ]; then
    log "simulate urban-$n"
    "$BIN" simulate --out "$GEN/urban-$n" --frames "$n" --seed 1 --profile urban
  fi
done

{
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git rev-parse --short HEAD) $(git diff --quiet && echo clean || echo dirty)"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //') x $(nproc)"
  echo "memory: $(free -g | awk '/Mem:/ {print $2}') GiB"
  echo "kernel: $(uname -r)"
  echo "rustc: $(rustc --version)"
  echo "reference: $($KISS_ODOM_PYTHON tests/reference/driver.py info)"
} > "$OUT/machine.txt"

if has speed; then
  mkdir -p "$OUT/speed"
  for ds in kitti-01 kitti-02 kitti-04 kitti-05 urban-500; do
    case $ds in
      kitti-*) path=$KITTI/sequences/${ds#kitti-}; rep=$REPEATS_KITTI; from=1 ;;
      *) path=$GEN/$ds; rep=$REPEATS_SIM; from=10 ;;
    esac
    for threads in 1 0; do
      for scalar in f64 f32; do
        name=$ds-t$threads-$scalar
        log "bench $name"
        "$BIN" bench "$path" --threads "$threads" --scalar "$scalar" --repeats "$rep" \
          --latency-from "$from" --json "$OUT/speed/$name.json" | tee "$OUT/speed/$name.txt"
      done
    done
  done
fi

if has rss; then
  # Peak RSS of `run` against sequence length: it must not grow.
  mkdir -p "$OUT/rss"
  for n in 250 500 1000 2000; do
    log "run urban-2000 frames ..$n"
    "$BIN" run "$GEN/urban-2000" --frames "..$n" --threads 1 --quiet --out "$OUT/rss/run-$n"
  done
fi

if has small; then
  # Small (microcontroller) configuration against full scale: accuracy and state bytes.
  mkdir -p "$OUT/small"
  for ds in kitti-01 kitti-02 kitti-04 kitti-05 urban-500; do
    case $ds in
      kitti-*) path=$KITTI/sequences/${ds#kitti-} ;;
      *) path=$GEN/$ds ;;
    esac
    log "small vs full on $ds"
    "$BIN" run "$path" --quiet --threads 1 --out "$OUT/small/$ds-full"
    "$BIN" run "$path" --quiet --threads 1 --max-range 50 --voxel-size 1 \
      --out "$OUT/small/$ds-full-50m"
    "$BIN" run "$path" --quiet --threads 1 --max-range 50 --voxel-size 1 \
      --capacities small --scalar f32 --storage quantized --out "$OUT/small/$ds-small"
  done
fi

if has tables; then
  log "voxel table: own open addressing vs hashbrown"
  cargo bench -p kiss-odom --bench voxel_table -- --noplot 2>&1 | tee "$OUT/voxel_table.txt"
fi

if has stages; then
  log "per-stage micro-benchmarks"
  cargo bench -p kiss-odom --bench stages -- --noplot 2>&1 | tee "$OUT/stages.txt"
fi

if has profile; then
  # Where the time goes: perf over single-thread runs (needs perf; not in the default STEPS).
  mkdir -p "$OUT/profile"
  for ds in kitti-05 urban-500; do
    case $ds in
      kitti-*) path=$KITTI/sequences/${ds#kitti-} ;;
      *) path=$GEN/$ds ;;
    esac
    log "perf on $ds"
    perf record -F 2000 -g -o "$OUT/profile/$ds.data" -- \
      "$BIN" bench "$path" --threads 1 --repeats 2 --no-reference > /dev/null
    perf report -i "$OUT/profile/$ds.data" --no-children --stdio --percent-limit 0.5 \
      -g none 2>/dev/null > "$OUT/profile/$ds.txt"
  done
fi

log "done: results in $OUT (python3 bench/summarize.py $OUT)"
