#!/usr/bin/env bash
# Reproduces the `live` table of BENCHMARKS.md section 7, "From recordings and the network":
# `kiss-odom live` fed by `kiss-odom replay` over loopback UDP, the OS-1-128
# recording (../shared/data/sensors/ouster, 3 sweeps) replayed N times at each rate. Prints a
# markdown table: sweeps whose last packet to pose time was measured (frames.csv
# pose_latency_ms), p50/p99/max of it, packets lost, and whether the poses are byte-equal to
# `run` on the file.
#
#   bench/live_latency.sh        (N=10 replays a rate by default)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
D=../shared/data/sensors/ouster
PCAP=$D/OS-1-128_v2.3.0_1024x10_lb_n3.pcap META=$D/OS-1-128_v2.3.0_1024x10.json
N=${N:-10}
out=target/bench/live-latency; rm -rf "$out"; mkdir -p "$out"
$B run "$PCAP" --calibration "$META" --out "$out/run" -q >/dev/null
echo "| rate | replays | sweeps timed | last packet to pose p50 / p99 / max (ms) | core p50 (ms) | packets lost | poses byte-equal to run |"
echo "|---|---|---|---|---|---|---|"
for rate in 1 5; do
  for i in $(seq "$N"); do
    o="$out/r$rate-$i"
    $B live --udp 127.0.0.1:17999 --calibration "$META" --out "$o" -q --idle-timeout 1 >/dev/null &
    live=$!
    # Listening once the port is taken.
    while python3 -c 'import socket; socket.socket(socket.AF_INET, socket.SOCK_DGRAM).bind(("127.0.0.1", 17999))' 2>/dev/null; do sleep 0.05; done
    $B replay "$PCAP" --to 127.0.0.1:17999 --rate "$rate" -q
    wait "$live"
  done
  python3 - "$out" "$rate" "$N" <<'P'
import csv, json, sys, glob, filecmp
out, rate, n = sys.argv[1:]
lat, core, lost, equal = [], [], 0, 0
for d in sorted(glob.glob(f"{out}/r{rate}-*")):
    rows = list(csv.DictReader(open(f"{d}/frames.csv")))
    lat += [float(r["pose_latency_ms"]) for r in rows if r["pose_latency_ms"]]
    core += [float(r["latency_ms"]) for r in rows if r["latency_ms"]]
    lost += json.load(open(f"{d}/summary.json"))["packets"]["lost"]
    equal += filecmp.cmp(f"{d}/poses_kitti.txt", f"{out}/run/poses_kitti.txt", shallow=False)
def pct(v, p):  # nearest rank, as the summaries
    v = sorted(v); return v[max(0, -(-len(v) * p // 100) - 1)]
print(f"| {rate}x | {n} | {len(lat)} | {pct(lat,50):.1f} / {pct(lat,99):.1f} / {max(lat):.1f} "
      f"| {pct(core,50):.1f} | {lost} | {equal} of {n} |")
P
done
