#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 13, "Default capacities: the map never fills" and
# "Capacities that fill": the default capacities on every shared recording and generated drive
# (no radius shrink, poses equal to kiss-icp 1.3.0's), then SMALL and TINY, which fill, against
# kiss-icp 1.3.0 at the radius the map shrank to.
#
#   KISS_ODOM_PYTHON=target/refvenv/bin/python bench/map_bound.sh
#
# OLD=path/to/kiss-odom adds a column for another build on the same runs (the eviction rule
# against one that refuses new voxels was compared that way). The generated drives go to $GEN
# (default target/bench/map-bound; seeds 41 and 42, never tuned on; made if missing); the
# reference comes from $KISS_ODOM_PYTHON (a venv from tests/reference/requirements.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
GEN=${GEN:-target/bench/map-bound}
PY=${KISS_ODOM_PYTHON:?a venv with kiss-icp 1.3.0}
DATA=../shared/data
mkdir -p "$GEN"
gen() { # name profile frames seed [sensor]
  [ -f "$GEN/$1/poses.txt" ] || $B simulate --profile "$2" --frames "$3" --seed "$4" \
    ${5:+--sensor $5} --out "$GEN/$1" --overwrite >/dev/null
}
gen urban-500-s41 urban 500 41
gen fast-500-s41 fast 500 41
gen field-500-s41 field 500 41
gen suburban-vlp16-500-s41 suburban 500 41 vlp16
gen urban-vlp16-500-s41 urban 500 41 vlp16
gen suburban-vlp16-1000-s42 suburban 1000 42 vlp16
K=$DATA/kitti-mini/sequences
S=$DATA/sensors
O=$S/ouster
status=0
python3 bench/map_bound.py defaults $B $K/01 $K/02 $K/04 $K/05 \
  "$O/OS-0-32-U1_v2.2.0_1024x10.pcap@--meta,$O/OS-0-32-U1_v2.2.0_1024x10.json" \
  "$O/OS-1-32-G_v2.1.1_1024x10.pcap@--meta,$O/OS-1-32-G_v2.1.1_1024x10.json" \
  "$O/OS-1-128_v2.3.0_1024x10_lb_n3.pcap@--meta,$O/OS-1-128_v2.3.0_1024x10.json" \
  $S/velodyne/velodyne_vlp16.pcap $S/velodyne/velodyne_vlp32.pcap \
  $GEN/urban-500-s41 $GEN/fast-500-s41 $GEN/field-500-s41 $GEN/suburban-vlp16-500-s41 \
  $GEN/suburban-vlp16-1000-s42 || status=1
echo
python3 bench/map_bound.py filled $B "${OLD:--}" "$PY" \
  tests/reference/driver.py $GEN/suburban-vlp16-500-s41 $GEN/urban-vlp16-500-s41 \
  $GEN/urban-500-s41 || status=1
exit $status
