#!/usr/bin/env bash
# Reproduces the rounding floor in BENCHMARKS.md section 7, "Generated recordings: pcap against
# direct points" (`N=12 bench/quantisation_floor.sh avia urban 1`, and seed 2).
# How far one generated drive's KITTI error moves when its direct points move by the size of
# the packets' rounding: N copies of the simulator's direct points, each coordinate moved by a
# uniform +-0.5 mm (Livox's 1 mm grid at a random offset; Hesai and Velodyne round the range
# to 4 and 2 mm), run like the direct points and the pcap (`kiss-odom run`, deskew on).
# The spread is the floor under which "pcap within X % of direct" cannot be told on that drive.
#
#   bench/quantisation_floor.sh SENSOR PROFILE SEED   (N=6, FRAMES=500, DATA=target/bench/qfloor;
#                                                      numpy from target/numpyvenv, made here)
set -euo pipefail
cd "$(dirname "$0")/.."
sensor=$1 profile=$2 seed=$3
N=${N:-6} FRAMES=${FRAMES:-500} DATA=${DATA:-target/bench/qfloor}
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
PY=target/numpyvenv/bin/python
[ -x "$PY" ] || { python3 -m venv target/numpyvenv && $PY -m pip install -q numpy; }
d="$DATA/$sensor-$profile-$seed"
[ -f "$d/sim.toml" ] || $B simulate --out "$d" --frames "$FRAMES" --seed "$seed" \
  --profile "$profile" --sensor "$sensor" --format pcap --overwrite >/dev/null
kitti() { $B eval --json "$1/poses_kitti.txt" "$d/poses.txt" | $PY -c \
  'import json, sys; m = json.load(sys.stdin); print("%.4f %.4f" % (m["kitti_t_err_pct"], m["ate_m"]))'; }
$B run "$d/packets.pcap" --set data.deskew=true --out "$d.pcap" -q >/dev/null
$B run "$d" --set data.deskew=true --out "$d.direct" -q >/dev/null
echo "pcap $(kitti "$d.pcap")"
echo "direct $(kitti "$d.direct")"
for k in $(seq 1 "$N"); do
  p="$d.moved$k"
  $PY - "$d" "$p" "$k" <<'P'
import os, shutil, sys
import numpy as np
src, dst, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
rng = np.random.default_rng(seed)
os.makedirs(dst + "/velodyne", exist_ok=True)
for f in ("sim.toml", "poses.txt", "times.txt"):
    shutil.copy(f"{src}/{f}", f"{dst}/{f}")
if not os.path.exists(dst + "/timestamps"):
    os.symlink(os.path.abspath(src + "/timestamps"), dst + "/timestamps")
for name in sorted(os.listdir(src + "/velodyne")):
    p = np.fromfile(f"{src}/velodyne/{name}", dtype="<f4").reshape(-1, 4)
    p[:, :3] += rng.uniform(-5e-4, 5e-4, size=(len(p), 3)).astype("<f4")
    p.tofile(f"{dst}/velodyne/{name}")
P
  $B run "$p" --set data.deskew=true --out "$p.run" -q >/dev/null
  echo "moved$k $(kitti "$p.run")"
  rm -rf "$p/velodyne"
done | tee "$d.moved.txt"
$PY - "$d.moved.txt" "$(kitti "$d.pcap")" <<'P'
import sys
v = [float(l.split()[1]) for l in open(sys.argv[1])]
pcap = float(sys.argv[2].split()[0])
mean = sum(v) / len(v)
print(f"moved direct points, {len(v)} runs: KITTI {min(v):.4f}-{max(v):.4f} % "
      f"(mean {mean:.4f}, spread {min(v) / mean:.3f}-{max(v) / mean:.3f} of it); "
      f"pcap / mean {pcap / mean:.3f}")
P
