#!/usr/bin/env bash
# rko_lio 0.4.0 (PyPI) on the drives bench/imu_prior.sh generated (drone-N, handheld-N under
# DATA), through bench/rko_lio_run.py, scored like ours with `kiss-odom eval` against the same
# ground truth. Prints one markdown row per drive: KITTI %, ATE m, RPE rad/frame.
#
#   bench/imu_peers.sh      (DATA=target/imu-prior, SEEDS="1 2 3"; the venv target/liovenv
#                            is made here: rko-lio==0.4.0, plyfile)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
DATA=${DATA:-target/imu-prior}
LIO=${LIO_VENV:-target/liovenv}
[ -x "$LIO/bin/rko_lio" ] || { python3 -m venv "$LIO" && "$LIO/bin/pip" install --quiet rko-lio==0.4.0 plyfile; }
for prof in ${PROFILES:-drone handheld}; do
  for seed in ${SEEDS:-1 2 3}; do
    d="$DATA/$prof-$seed"; o="$DATA/$prof-$seed.rko_lio"
    "$LIO/bin/python" bench/rko_lio_run.py "$d" "$o" 2>/dev/null | tail -1 >&2
    $B eval --json "$o/poses_kitti.txt" "$o/ground_truth.txt" | python3 -c "
import json, sys
m = json.load(sys.stdin)
k = m['kitti_t_err_pct']
print(f\"| $prof | $seed | rko_lio 0.4.0 | {k if k is None else f'{k:.3f}'} | {m['ate_m']:.3f} | {m['rpe_rad_mean']:.4f} | {m['frames']} frames |\")"
  done
done
