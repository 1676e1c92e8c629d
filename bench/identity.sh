#!/usr/bin/env bash
# Poses of every mode on real and generated data, as one sha256 per run: run it before and
# after a change that must not move any pose (a restructuring), then diff the two outputs.
# Cases: the four kitti-mini sequences, the Ouster OS-1-128 recording, a generated urban drive
# (deskewed) and a generated hand-held walk with an IMU; modes: the default (f64 and f32), the
# accurate preset (f64 and f32), robust mode, and the gyroscope prior.
#
# Usage: bash bench/identity.sh [KISS_ODOM_BIN] > poses.sha256   (default: target/release/kiss-odom)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${1:-target/release/kiss-odom}
DATA=../shared/data
WORK=target/bench/identity
mkdir -p "$WORK"
if [ ! -f "$WORK/urban/sim.toml" ]; then
  "$BIN" simulate --out "$WORK/urban" --profile urban --seed 3 --frames 60 --beams 32 \
    --columns 512 >/dev/null
fi
if [ ! -f "$WORK/handheld/sim.toml" ]; then
  "$BIN" simulate --out "$WORK/handheld" --profile handheld --seed 5 --frames 60 --beams 32 \
    --columns 512 --imu-rate 200 >/dev/null
fi
OUSTER=$DATA/sensors/ouster/OS-1-128_v2.3.0_1024x10_lb_n3
inputs=(
  "kitti01|$DATA/kitti-mini/sequences/01"
  "kitti02|$DATA/kitti-mini/sequences/02"
  "kitti04|$DATA/kitti-mini/sequences/04"
  "kitti05|$DATA/kitti-mini/sequences/05"
  "ouster|$OUSTER.pcap --calibration $DATA/sensors/ouster/OS-1-128_v2.3.0_1024x10.json"
  "urban|$WORK/urban"
  "handheld|$WORK/handheld"
)
modes=(
  "default|"
  "default-f32|--set runtime.scalar=f32"
  "accurate|--preset accurate"
  "accurate-f32|--preset accurate --set runtime.scalar=f32"
  "robust|--set registration.degeneracy=robust"
)
run() { # run NAME INPUT ARGS...
  local name=$1 input=$2
  shift 2
  # shellcheck disable=SC2086
  "$BIN" run $input "$@" --threads 1 --quiet --out "$WORK/out/$name" 2>/dev/null
  echo "$(sha256sum <"$WORK/out/$name/poses_kitti.txt" | cut -c1-16)  $name"
}
for i in "${inputs[@]}"; do
  for m in "${modes[@]}"; do
    # shellcheck disable=SC2086
    run "${i%%|*}-${m%%|*}" "${i#*|}" ${m#*|}
  done
done
run handheld-imu "$WORK/handheld" --imu auto
run handheld-imu-accurate "$WORK/handheld" --imu auto --preset accurate
