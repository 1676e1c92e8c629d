#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 15, "Speed against kiss-icp": bench/accurate_fps.py on the
# four kitti-mini sequences and the generated urban drive of the preset's table (urban-500-s1,
# the same folder bench/accurate.sh makes), kiss-icp 1.3.0 and both presets alternating, best
# of REPEATS (default 5). Run it alone on the machine: it times.
#
#   bash bench/accurate_fps.sh
#
# The venv is bench/python.sh's (target/pyvenv: kiss-icp 1.3.0 and the `kiss_odom` package).
set -euo pipefail
cd "$(dirname "$0")/.."
bash bench/python.sh venv
cargo build --release -q -p kiss-odom --features dev
BIN=${CARGO_TARGET_DIR:-target}/release/kiss-odom
GEN=${GEN:-target/bench/accurate}
d=$GEN/urban-500-s1
[ -f "$d/poses.txt" ] || "$BIN" simulate --out "$d" --frames 500 --seed 1 --profile urban >/dev/null
K=../shared/data/kitti-mini/sequences
DEV=${CARGO_TARGET_DIR:-target}/release/kiss-odom-dev "${PY:-target/pyvenv}/bin/python" bench/accurate_fps.py --repeats "${REPEATS:-5}" \
  "$K/01" "$K/02" "$K/04" "$K/05" "$d"
