#!/usr/bin/env bash
# Reproduces the peers' columns of BENCHMARKS.md section 14, "Against LiDAR only and
# LiDAR-inertial peers": rko_lio 0.4.0, GenZ-LIO 0.1.1 and pelorus 0.0.8 (PyPI) on the drives
# bench/imu_prior.sh
# generated (drone-N, handheld-N under DATA), through bench/{rko_lio,genz_lio,pelorus}_run.py,
# scored like ours with `kiss-odom eval` against the same ground truth. Prints one markdown row
# per drive and peer: KITTI %, ATE m, RPE rad/frame.
#
#   bench/imu_peers.sh      (after bench/imu_prior.sh; DATA=target/bench/imu, SEEDS="1 2 3", PEERS="rko_lio genz_lio
#                            pelorus"; the venv target/liovenv is made here: rko-lio==0.4.0,
#                            plyfile, genz-lio==0.1.1, pelorus==0.0.8; BIN=a kiss-odom
#                            to score with)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${BIN:-target/release/kiss-odom}
[ -n "${BIN:-}" ] || cargo build --release -q -p kiss-odom
DATA=${DATA:-target/bench/imu}
LIO=${LIO_VENV:-target/liovenv}
[ -x "$LIO/bin/python" ] || python3 -m venv "$LIO"
"$LIO/bin/python" -c "import rko_lio, plyfile, genz_lio, pelorus" 2>/dev/null ||
  "$LIO/bin/pip" install --quiet rko-lio==0.4.0 plyfile genz-lio==0.1.1 pelorus==0.0.8
declare -A VERSION=([rko_lio]="rko_lio 0.4.0" [genz_lio]="GenZ-LIO 0.1.1" [pelorus]="pelorus 0.0.8")
for prof in ${PROFILES:-drone handheld}; do
  for seed in ${SEEDS:-1 2 3}; do
    for peer in ${PEERS:-rko_lio genz_lio pelorus}; do
      d="$DATA/$prof-$seed"; o="$DATA/$prof-$seed.$peer"
      "$LIO/bin/python" "bench/${peer}_run.py" "$d" "$o" 2>/dev/null | tail -1 >&2
      $B eval --json "$o/poses_kitti.txt" "$o/ground_truth.txt" | python3 -c "
import json, sys
m = json.load(sys.stdin)
k = m['kitti_t_err_pct']
print(f\"| $prof | $seed | ${VERSION[$peer]} | {k if k is None else f'{k:.3f}'} | {m['ate_m']:.3f} | {m['rpe_rad_mean']:.4f} | {m['frames']} frames |\")"
    done
  done
done
