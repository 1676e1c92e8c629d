#!/usr/bin/env bash
# Reproduces the speed line of BENCHMARKS.md section 13, "The host's default run": `bench`
# (kiss-odom against kiss-icp 1.3.0 on preloaded frames, one thread, the ratio of frames/s in the
# same run) with a build from before the host grew its storage and with this one, on kitti-mini 01
# and 05 and a generated urban drive (seed 61, 100 frames).
#
#   KISS_ODOM_PYTHON=target/refvenv/bin/python bash bench/growth_speed.sh OLD_BIN [NEW_BIN]
#
# OLD_BIN: a kiss-odom built from an earlier commit (git worktree add ../old COMMIT; cargo
# build --release -p kiss-odom there). NEW_BIN defaults to this tree's release build.
set -euo pipefail
cd "$(dirname "$0")/.."
OLD=${1:?a kiss-odom built before the change}
NEW=${2:-target/release/kiss-odom-dev}
: "${KISS_ODOM_PYTHON:?a venv with kiss-icp 1.3.0}"
OUT=target/bench/growth-speed
mkdir -p "$OUT"
U=$OUT/urban-100-s61
[ -f "$U/poses.txt" ] || target/release/kiss-odom simulate --profile urban --frames 100 --seed 61 --out "$U" \
  --overwrite >/dev/null
K=../shared/data/kitti-mini/sequences
echo "| dataset | before: ours / kiss-icp frames/s | after: ours / kiss-icp frames/s |"
echo "|---|---|---|"
for d in "$K/01" "$K/05" "$U"; do
  row="| $(basename "$d") |"
  for b in "$OLD" "$NEW"; do
    "$b" bench "$d" --repeats 3 --threads 1 --json "$OUT/bench.json" >/dev/null 2>&1
    row="$row $(python3 -c "import json; j = json.load(open('$OUT/bench.json')); \
print(f\"{j['speed_ratio']:.2f}x ({', '.join(f'{r:.2f}' for r in j['speed_ratio_runs'])})\")") |"
  done
  echo "$row"
done
