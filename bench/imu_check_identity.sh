#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 14, "A wrong IMU" (its "right" row: a right IMU is never
# rejected): every run of bench/imu_prior.sh (the table "Against LiDAR only and LiDAR-inertial
# peers" and the variants of its "Tried and dropped") with two builds, BEFORE (a kiss-odom
# built without the IMU consistency check) and BIN (this tree's): their poses_kitti.txt must
# be the same bytes, and no frame of BIN's may have `imu_prior` = `rejected`. Prints one
# markdown row per run: drive, variant, frames, frames rejected, frames with refused samples,
# poses identical.
#
#   BEFORE=/path/to/kiss-odom bench/imu_check_identity.sh
#       (DATA=target/bench/imu-identity, SEEDS="1 2 3", BIN=a kiss-odom to use; each seed's
#        drives are simulated, run with both builds and deleted (KEEP=1 keeps them: 2.2 GB a
#        seed); BEFORE's outputs are kept and not rerun; about 30 min a seed and build)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${BEFORE:?BEFORE=path to a kiss-odom without the check}"
B=${BIN:-target/release/kiss-odom}
[ -n "${BIN:-}" ] || cargo build --release -q -p kiss-odom
DATA=${DATA:-target/bench/imu-identity}; mkdir -p "$DATA/before" "$DATA/after"
# bench/imu_prior.sh's output folders of a seed's drives: drive.variant.
outputs() { find "$DATA" -maxdepth 1 -type d -name "*-$1.*"; }
for seed in ${SEEDS:-1 2 3}; do
  if [ ! -f "$DATA/before/$seed.done" ]; then
    BIN=$BEFORE DATA=$DATA SEEDS=$seed bench/imu_prior.sh > "$DATA/before/table-$seed.md"
    outputs "$seed" | while read -r o; do rm -rf "$DATA/before/${o##*/}"; mv "$o" "$DATA/before/"; done
    touch "$DATA/before/$seed.done"
  fi
  BIN=$B DATA=$DATA SEEDS=$seed bench/imu_prior.sh > "$DATA/after/table-$seed.md"
  outputs "$seed" | while read -r o; do rm -rf "$DATA/after/${o##*/}"; mv "$o" "$DATA/after/"; done
  [ "${KEEP:-0}" = 1 ] || rm -rf "$DATA/drone-$seed" "$DATA/handheld-$seed"
done
python3 - "$DATA" ${SEEDS:-1 2 3} <<'P'
import csv, os, sys
data, seeds = sys.argv[1], sys.argv[2:]
print("| drive | variant | frames | rejected | with refused samples | poses identical |")
print("|---|---|---|---|---|---|")
bad = 0
for run in sorted(os.listdir(f"{data}/after")):
    drive, _, variant = run.partition(".")
    if not variant or drive.rsplit("-", 1)[-1] not in seeds:
        continue
    before, after = (open(f"{data}/{w}/{run}/poses_kitti.txt", "rb").read() for w in ("before", "after"))
    rows = list(csv.DictReader(open(f"{data}/after/{run}/frames.csv")))
    rejected = sum(r.get("imu_prior") == "rejected" for r in rows)
    refused = sum(int(r.get("imu_refused") or 0) > 0 for r in rows)
    same = before == after
    bad += rejected + refused + (not same)
    print(f"| {drive} | {variant.replace('_', ' ')} | {len(rows)} | {rejected} | {refused} | {'yes' if same else 'NO'} |")
sys.exit(1 if bad else 0)
P
