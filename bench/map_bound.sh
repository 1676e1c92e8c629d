#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 13, "The host's map never evicts" and "Capacities that
# fill": the host's default (growing) run on every shared recording, every generated profile
# (500 frames) and a long forest drive whose map grows several times past the starting
# capacities (no eviction, poses within the crosscheck's tolerance of kiss-icp 1.3.0 on every
# frame, the state's bytes beside kiss-icp's peak RSS), then SMALL and TINY, which fill,
# against kiss-icp 1.3.0 at r_max and at the radius the map shrank to.
#
#   KISS_ODOM_PYTHON=target/refvenv/bin/python bash bench/map_bound.sh
#
# FOREST_FRAMES (default 1000, about 1 km) sets the forest drive's length; 0 leaves it out.
# OLD=path/to/kiss-odom adds a column for another build in the second table. The generated
# drives go to $GEN (default target/bench/map-bound; seeds 41, 42 and for the forest 43, never
# tuned on; the forest's densities were set on seed 41; made if missing); the reference comes
# from $KISS_ODOM_PYTHON (a venv from tests/reference/requirements.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom --features dev
B=target/release/kiss-odom
export KISS_ODOM_DEV=target/release/kiss-odom-dev
GEN=${GEN:-target/bench/map-bound}
PY=${KISS_ODOM_PYTHON:?a venv with kiss-icp 1.3.0}
DATA=../shared/data
FOREST_FRAMES=${FOREST_FRAMES:-1000}
mkdir -p "$GEN"
gen() { # name profile frames seed [simulate flags...]
  [ -f "$GEN/$1/poses.txt" ] || $B simulate --profile "$2" --frames "$3" --seed "$4" \
    "${@:5}" --out "$GEN/$1" --overwrite >/dev/null
}
PROFILES=()
for p in urban corridor fast plane tunnel field handheld drone warehouse; do
  gen "$p-500-s41" "$p" 500 41
  PROFILES+=("$GEN/$p-500-s41")
done
gen suburban-vlp16-500-s41 suburban 500 41 --sensor vlp16
gen urban-vlp16-500-s41 urban 500 41 --sensor vlp16
gen suburban-vlp16-1000-s42 suburban 1000 42 --sensor vlp16
PROFILES+=("$GEN/suburban-vlp16-500-s41" "$GEN/suburban-vlp16-1000-s42")
if [ "$FOREST_FRAMES" -gt 0 ]; then
  # An OS0-128's geometry: 128 beams over 90 degrees see the canopy overhead.
  gen "forest-$FOREST_FRAMES-s43" forest "$FOREST_FRAMES" 43 --beams 128 --columns 2048 \
    --fov-up 45 --fov-down -45
  PROFILES+=("$GEN/forest-$FOREST_FRAMES-s43")
fi
K=$DATA/kitti-mini/sequences
S=$DATA/sensors
O=$S/ouster
status=0
python3 bench/map_bound.py defaults $B "$PY" tests/reference/driver.py \
  $K/01 $K/02 $K/04 $K/05 \
  "$O/OS-0-32-U1_v2.2.0_1024x10.pcap@--calibration,$O/OS-0-32-U1_v2.2.0_1024x10.json" \
  "$O/OS-1-32-G_v2.1.1_1024x10.pcap@--calibration,$O/OS-1-32-G_v2.1.1_1024x10.json" \
  "$O/OS-1-128_v2.3.0_1024x10_lb_n3.pcap@--calibration,$O/OS-1-128_v2.3.0_1024x10.json" \
  $S/velodyne/velodyne_vlp16.pcap $S/velodyne/velodyne_vlp32.pcap \
  $S/hesai/hesai-xt32-small.pcap $S/livox/livox_tele15_small.pcap \
  "${PROFILES[@]}" || status=1
echo
python3 bench/map_bound.py filled $B "${OLD:--}" "$PY" \
  tests/reference/driver.py $GEN/suburban-vlp16-500-s41 $GEN/urban-vlp16-500-s41 \
  $GEN/urban-500-s41 || status=1
exit $status
