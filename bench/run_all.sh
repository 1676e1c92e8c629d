#!/usr/bin/env bash
# Reproduces the host's speed, memory and build tables of BENCHMARKS.md, one step each:
#
#   crosscheck  section 1, "Stages", "Whole sequences", "f32 build"
#   speed       section 2, the all-threads ratios, and section 3's "High-water marks and
#               margins" (the clouds) and "The map against the reference's" (the reference's
#               map and RSS), printed by bench/summarize.py
#   rss         section 6, "Long run and tooling": peak RSS flat over the sequence length
#   state       section 3, "State bytes of each capacity preset"
#   small       section 3, the small configuration's accuracy (bench/summarize.py)
#   tables      section 4, the voxel table against hashbrown (criterion)
#   rerun       section 11, "Cost of `--rerun` on the README run" (builds `--features rerun`)
#   build       sections 9 and 11, the build costs (three clean release builds)
#
#   bench/run_all.sh                      # the default steps: speed rss small tables
#   STEPS="state crosscheck" bench/run_all.sh
#
# Results go to $OUT (JSON and text per measurement; default target/bench/run-all/results);
# `python3 bench/summarize.py $OUT` prints the speed, RSS and small-configuration tables. The
# other steps print their table as they go. Generated drives go to $GEN (default
# target/bench/run-all) and are made once. The reference kiss-icp 1.3.0 runs from
# $KISS_ODOM_PYTHON (default target/refvenv/bin/python: a venv made from
# tests/reference/requirements.txt, as .ci/run makes it). The default steps take about 40 min
# on 2 shared cores; `build` about an hour.
set -euo pipefail
cd "$(dirname "$0")/.."

export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-target}
export KISS_ODOM_PYTHON=${KISS_ODOM_PYTHON:-$PWD/target/refvenv/bin/python}
KITTI=${KISS_ODOM_KITTI_MINI:-../shared/data/kitti-mini}
GEN=${GEN:-target/bench/run-all}
OUT=${OUT:-$GEN/results}
STEPS=${STEPS:-"speed rss small tables"}
# Timed runs per implementation and configuration (each after one untimed warm-up run).
REPEATS_KITTI=${REPEATS_KITTI:-5}
REPEATS_SIM=${REPEATS_SIM:-3}

has() { [[ " $STEPS " == *" $1 "* ]]; }
log() { printf '\n=== %s\n' "$*"; }

cargo build --release -p kiss-odom --features dev
BIN=$CARGO_TARGET_DIR/release/kiss-odom
DEV=$CARGO_TARGET_DIR/release/kiss-odom-dev
mkdir -p "$OUT" "$GEN"

# The generated sequences (the simulator's bytes depend on the seed and flags only).
sim() { # name frames seed
  if [ ! -f "$GEN/$1/poses.txt" ]; then
    log "simulate $1"
    "$BIN" simulate --out "$GEN/$1" --frames "$2" --seed "$3" --profile urban >/dev/null
  fi
}
if has speed || has small; then sim urban-500 500 1; fi
if has rss; then sim urban-2000 2000 1; fi
if has crosscheck; then sim crosscheck-urban-1000 1000 7; fi

{
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git rev-parse --short HEAD) $(git diff --quiet && echo clean || echo dirty)"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //') x $(nproc)"
  echo "memory: $(free -g | awk '/Mem:/ {print $2}') GiB"
  echo "kernel: $(uname -r)"
  echo "rustc: $(rustc --version)"
  if [ -x "$KISS_ODOM_PYTHON" ]; then
    echo "reference: $($KISS_ODOM_PYTHON tests/reference/driver.py info)"
  fi
} > "$OUT/machine.txt"

if has crosscheck; then
  # Stage by stage and end to end against kiss-icp 1.3.0; exit 1 on any breach of a tolerance.
  mkdir -p "$OUT/crosscheck"
  for s in 01 02 04 05; do
    log "crosscheck kitti-mini $s"
    "$DEV" crosscheck "$KITTI/sequences/$s" --set runtime.scalar=f32 --table markdown \
      --json "$OUT/crosscheck/kitti-$s.json"
  done
  log "crosscheck ncd-ouster-deskew"
  "$DEV" crosscheck ../shared/data/ncd-ouster-deskew --table markdown \
    --json "$OUT/crosscheck/ouster.json"
  log "crosscheck urban-1000"
  "$DEV" crosscheck "$GEN/crosscheck-urban-1000" --set runtime.scalar=f32 --table markdown \
    --json "$OUT/crosscheck/urban-1000.json"
fi

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
        "$DEV" bench "$path" --threads "$threads" --set runtime.scalar="$scalar" --repeats "$rep" \
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

if has state; then
  # The core's state (summary.json's state_bytes) for each capacity preset and build: fixed at
  # start whatever the data, so one frame of the shipped sample is enough.
  mkdir -p "$OUT/state"
  echo "| capacities | f32, quantized map points | f64, exact map points |"
  echo "|---|---|---|"
  for c in tiny small full; do
    row="| $c"
    for build in "f32 quantized" "f64 exact"; do
      set -- $build
      o="$OUT/state/$c-$1"
      "$BIN" run fixtures/kitti-05-reduced --out "$o" --quiet --frames ..1 \
        --set capacities="$c" --set runtime.scalar="$1" --set runtime.map_storage="$2" >/dev/null
      row="$row | $(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["state_bytes"], "B")' "$o/summary.json")"
    done
    echo "$row |"
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
    "$BIN" run "$path" --quiet --threads 1 --max-range 50 --set mapping.voxel_size=1 \
      --out "$OUT/small/$ds-full-50m"
    "$BIN" run "$path" --quiet --threads 1 --max-range 50 --set mapping.voxel_size=1 \
      --set capacities=small --set runtime.scalar=f32 --set runtime.map_storage=quantized --out "$OUT/small/$ds-small"
  done
fi

if has tables; then
  log "voxel table: own open addressing vs hashbrown"
  cargo bench -p kiss-odom-drive --bench voxel_table -- --noplot 2>&1 | tee "$OUT/voxel_table.txt"
fi

if has rerun; then
  # Wall time of the whole README run with and without `--rerun`, five alternating pairs, and
  # the core's rate (summary.json's hz); the poses must be byte-equal.
  RR=$GEN/rerun-target
  log "build --features rerun (into $RR)"
  CARGO_TARGET_DIR=$RR cargo build --release -q -p kiss-odom --features rerun
  mkdir -p "$OUT/rerun"
  for i in 1 2 3 4 5; do
    for mode in plain rerun; do
      extra=(); [ $mode = rerun ] && extra=(--rerun "$OUT/rerun/run.rrd")
      s=$(date +%s.%N)
      "$RR/release/kiss-odom" run fixtures/kitti-05-reduced --out "$OUT/rerun/$mode" --quiet "${extra[@]}"
      e=$(date +%s.%N)
      hz=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["hz"])' "$OUT/rerun/$mode/summary.json")
      echo "$mode $(python3 -c "print(f'{$e - $s:.3f}')") s, core $hz Hz" | tee -a "$OUT/rerun/times.txt"
    done
  done
  cmp "$OUT/rerun/plain/poses_kitti.txt" "$OUT/rerun/rerun/poses_kitti.txt" && echo "poses byte-equal"
fi

if has build; then
  # Clean release builds in empty target folders, CPU time (user + sys) and wall time from
  # /usr/bin/time: the default build, `--features rerun` on top of it, and `--features ros2`
  # from empty again.
  B=$GEN/cleanbuild
  rm -rf "$B" && mkdir -p "$B"
  timed() { # label target-dir cargo-args...
    local label=$1 dir=$2; shift 2
    CARGO_TARGET_DIR=$dir /usr/bin/time -f "%U %S %e" -o "$B/$label.time" cargo build --release -q "$@"
    awk -v l="$label" '{ printf "| %s | %.0f s (%.0f + %.0f) | %.0f s |\n", l, $1 + $2, $1, $2, $3 }' "$B/$label.time"
  }
  echo "| build | CPU (user + sys) | wall |"
  echo "|---|---|---|"
  timed "default features, clean" "$B/default" -p kiss-odom
  timed "--features rerun on top of it" "$B/default" -p kiss-odom --features rerun
  timed "--features ros2, clean" "$B/ros2" -p kiss-odom --features ros2
fi

log "done: results in $OUT (python3 bench/summarize.py $OUT)"
