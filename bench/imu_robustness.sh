#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 14, "Where it should not help, and wrong facts" (the table and
# its paragraph on the IMU stopping): what the gyroscope prior does where it should not help or is given wrong facts,
# against the
# LiDAR-only run of the same drive: car drives (urban, fast: the constant-velocity model suits
# them), and a drone flight with the IMU's extrinsic rotated by 5 degrees, its clock shifted by
# 20 ms, or its samples stopping half-way. Prints markdown rows: KITTI %, ATE m, frames used.
#
#   bench/imu_robustness.sh     (DATA=target/bench/imu, SEED=1; drone-SEED from
#                                bench/imu_prior.sh is reused when there; STOPS="25", the
#                                times in s at which the IMU stops, one run each)
#   for s in 1 2 3; do SEED=$s STOPS="0.5 5 15 25 35" bench/imu_robustness.sh; done
set -euo pipefail
cd "$(dirname "$0")/.."
B=${BIN:-target/release/kiss-odom}
[ -n "${BIN:-}" ] || cargo build --release -q -p kiss-odom
DATA=${DATA:-target/bench/imu}; SEED=${SEED:-1}; mkdir -p "$DATA"
row() { # drive, variant, run folder
  python3 - "$1" "$2" "$3" <<'P'
import csv, json, sys
drive, variant, out = sys.argv[1:]
m = json.load(open(f"{out}/summary.json"))["metrics"]
used = sum(r["imu_prior"] == "used" for r in csv.DictReader(open(f"{out}/frames.csv")))
print(f"| {drive} | {variant} | {m['kitti_t_err_pct']:.3f} | {m['ate_m']:.3f} | {used} |")
P
}
echo "| drive | variant | KITTI % | ATE m | frames with the prior |"
echo "|---|---|---|---|---|"
for prof in urban fast; do
  d="$DATA/$prof-$SEED"
  [ -f "$d/imu.csv" ] || $B simulate --out "$d" --frames 500 --seed "$SEED" --profile "$prof" \
    --imu-rate 200 --overwrite >/dev/null
  $B run "$d" --out "$d.off" -q 2>/dev/null; row "$prof $SEED" "LiDAR only" "$d.off"
  $B run "$d" --imu auto --out "$d.prior" -q 2>/dev/null; row "$prof $SEED" "prior" "$d.prior"
done
d="$DATA/drone-$SEED"
[ -f "$d/imu.csv" ] || $B simulate --out "$d" --frames 500 --seed "$SEED" --profile drone \
  --imu-rate 200 --overwrite >/dev/null
$B run "$d" --out "$d.off" -q 2>/dev/null; row "drone $SEED" "LiDAR only" "$d.off"
$B run "$d" --imu auto --out "$d.prior" -q 2>/dev/null; row "drone $SEED" "prior" "$d.prior"
$B run "$d" --imu auto --set "imu.extrinsic=[0,0,0,5,0,0]" --out "$d.rot5" -q 2>/dev/null
row "drone $SEED" "prior, extrinsic off by 5 deg (roll)" "$d.rot5"
$B run "$d" --imu auto --set imu.time_offset=0.02 --out "$d.shift20" -q 2>/dev/null
row "drone $SEED" "prior, clock off by 20 ms" "$d.shift20"
# The IMU stops after each of STOPS s (default: 25, half-way): the later samples are gone.
for t in ${STOPS:-25}; do
  stop="$DATA/drone-$SEED-imu-stops-$t"
  rm -rf "$stop" && mkdir -p "$stop"
  for f in velodyne timestamps poses.txt times.txt sim.toml; do ln -s "$(realpath "$d/$f")" "$stop/$f"; done
  awk -F, -v t="$t" 'NR == 1 || $1 < t' "$d/imu.csv" > "$stop/imu.csv"
  $B run "$stop" --imu auto --out "$stop.run" -q 2>/dev/null
  row "drone $SEED" "prior, IMU stops at $t s" "$stop.run"
done
