#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 7, "Generated recordings: pcap against direct points" (with
# CROSSCHECK=1 also its comparison with kiss-icp 1.3.0 on the same decoded points):
# `kiss-odom run` on generated sensor recordings (packets) against the same run on the
# simulator's direct point output (the exact points the packets were made from), deskew on and
# off. VLP-16 and OS1-64 (and, with SPECS, the Mid-360, XT32, Avia, QT128, OT128, XT16, XT32M,
# Pandar40P, Pandar64, QT64, AT128, Helios, Airy, HDL-64E S3, VLS-128, RS-M1 and E1R), urban and fast,
# 500 sweeps each, seeds 1-3. Prints a markdown table of KITTI relative translation error and ATE against
# the simulator's ground truth, per drive and the mean over the seeds (a single drive's error is a random walk that the packets' range
# quantisation, 1-2 mm, already perturbs: compare means).
#
#   bench/sensors_pcap.sh        (DATA=target/bench/sensors-pcap, FRAMES=500, SEEDS="1 2 3",
#                                 SPECS="vlp16 urban,vlp16 fast,os1-64 urban,os1-64 fast"; each
#                                 drive, up to 1.2 GB, is removed after its runs unless KEEP=1;
#                                 ROWS=... appends to an earlier run's rows.tsv instead;
#                                 KISS_ODOM_BIN=... runs that binary instead of building one;
#                                 CROSSCHECK=1 also runs `crosscheck` on each drive's pcap
#                                 against kiss-icp 1.3.0 from $KISS_ODOM_PYTHON, into
#                                 DATA/crosscheck.txt)
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${KISS_ODOM_BIN:-}" ]; then cargo build --release -q -p kiss-odom --features dev; fi
B=${KISS_ODOM_BIN:-target/release/kiss-odom}
DATA=${DATA:-target/bench/sensors-pcap}; mkdir -p "$DATA"
FRAMES=${FRAMES:-500}
rows=${ROWS:-$DATA/rows.tsv}; [ -n "${ROWS:-}" ] || : > "$rows"
IFS=, read -ra specs <<< "${SPECS:-vlp16 urban,vlp16 fast,os1-64 urban,os1-64 fast}"
for spec in "${specs[@]}"; do
  for seed in ${SEEDS:-1 2 3}; do
    set -- $spec; d="$DATA/$1-$2-$seed"
    [ -f "$d/sim.toml" ] || $B simulate --out "$d" --frames "$FRAMES" --seed "$seed" \
      --profile "$2" --sensor "$1" --format pcap --overwrite >/dev/null
    case $1 in
      os1-64) src=(--calibration "$d/packets.json") ;;
      # Livox frames by time, found by port; the XT32 by its packets, sweeps by azimuth
      # coverage; the RS-M1 and E1R by their packets, frames by sequence number: nothing
      # to give.
      mid360|avia|xt32|m1|e1r) src=() ;;
      # Found by their packets too, with the angle correction file written beside (the
      # AT128's: the .dat).
      qt128|ot128|xt16|xt32m|pandar40p|pandar64|qt64) src=(--calibration "$d/packets.csv") ;;
      at128) src=(--calibration "$d/packets.dat") ;;
      # Named, as their packets do not say which model (the Velodynes with the calibration
      # written beside; the Robosense angles are in the DIFOP packet), cut at 0 degrees.
      vlp32ab|hdl64e-s2|hdl64e-s3|vls128)
        src=(--sensor "$1" --calibration "$d/packets.yaml" --set input.cut_angle=0) ;;
      rs16|rs32|bpearl|helios|helios16p|ruby|airy) src=(--sensor "$1" --set input.cut_angle=0) ;;
      *) src=(--set input.cut_angle=0) ;;
    esac
    for deskew in deskew no-deskew; do
      on=$([ "$deskew" = deskew ] && echo true || echo false)
      $B run "$d/packets.pcap" "${src[@]}" --set data.deskew=$on --out "$d.pcap.$deskew" -q \
        >/dev/null
      $B run "$d" --set data.deskew=$on --out "$d.direct.$deskew" -q >/dev/null
      for kind in pcap direct; do
        m=$($B eval --json "$d.$kind.$deskew/poses_kitti.txt" "$d/poses.txt")
        printf '%s\t%s\t%s\t%s\t%s\n' "$1 $2" "$seed" "$deskew" "$kind" "$(tr -d '\n ' <<< "$m")" >> "$rows"
      done
    done
    if [ "${CROSSCHECK:-0}" = 1 ]; then
      echo "== $1 $2 seed $seed" >> "$DATA/crosscheck.txt"
      "${KISS_ODOM_DEV:-target/release/kiss-odom-dev}" crosscheck "$d/packets.pcap" "${src[@]}" --only end-to-end --table markdown \
        >> "$DATA/crosscheck.txt"
    fi
    [ "${KEEP:-0}" = 1 ] || rm -rf "$d"
  done
done
python3 - "$rows" "$FRAMES" <<'P'
import json, sys
from collections import defaultdict
rows, frames = sys.argv[1], sys.argv[2]
r = defaultdict(dict)
for line in open(rows):
    drive, seed, deskew, kind, m = line.rstrip("\n").split("\t")
    r[(drive, deskew, seed)][kind] = json.loads(m)
print(f"| drive ({frames} sweeps) | deskew | seed | pcap: KITTI % / ATE m | direct points: KITTI % / ATE m | pcap / direct KITTI |")
print("|---|---|---|---|---|---|")
groups = defaultdict(list)
for (drive, deskew, seed), v in r.items():
    p, q = v["pcap"], v["direct"]
    on = "on" if deskew == "deskew" else "off"
    groups[(drive, on)].append((p, q))
    print(f"| {drive} | {on} | {seed} | {p['kitti_t_err_pct']:.3f} / {p['ate_m']:.3f} | "
          f"{q['kitti_t_err_pct']:.3f} / {q['ate_m']:.3f} | {p['kitti_t_err_pct'] / q['kitti_t_err_pct']:.3f} |")
for (drive, on), v in groups.items():
    mp = sum(p["kitti_t_err_pct"] for p, _ in v) / len(v)
    mq = sum(q["kitti_t_err_pct"] for _, q in v) / len(v)
    ap = sum(p["ate_m"] for p, _ in v) / len(v)
    aq = sum(q["ate_m"] for _, q in v) / len(v)
    print(f"| **{drive}, mean of {len(v)}** | {on} | | {mp:.3f} / {ap:.3f} | {mq:.3f} / {aq:.3f} | **{mp / mq:.3f}** |")
P
