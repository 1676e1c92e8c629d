#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 10, "TINY: a 16-beam sensor in 455 KiB":
# TINY (f32, quantized map, Capacities::TINY, Config::tiny's r_max 50 m, v 2 m,
# N_max 10) against FULL_SCALE f64 exact with the same parameters, on generated VLP-16 drives
# (16 beams, 1800 columns, +-15 degrees, 10 Hz), 500 sweeps each. Prints a markdown table:
# ATE and KITTI relative error of both, their ratio, and TINY's capacity drops.
#
#   bench/tiny.sh            (DATA=target/bench/tiny by default; the drives are made if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
DATA=${DATA:-target/bench/tiny}; mkdir -p "$DATA"
out=$DATA/runs; mkdir -p "$out"
# FULL_SCALE with TINY's parameters (Config::tiny), so that only capacities and scalar differ.
printf '[data]\nmax_range = 50.0\n[mapping]\nvoxel_size = 2.0\nmax_points_per_voxel = 10\n' > "$out/full.toml"
echo "| run | FULL_SCALE f64: ATE m / KITTI % | TINY f32 quantized: ATE m / KITTI % | TINY / FULL ATE | TINY frames with drops | TINY state B |"
echo "|---|---|---|---|---|---|"
for spec in "urban 11" "urban 12" "urban 13" "fast 11"; do
  set -- $spec; d="$DATA/vlp16-$1-$2"
  [ -f "$d/sim.toml" ] || $B simulate --out "$d" --frames 500 --seed "$2" --profile "$1" \
    --beams 16 --columns 1800 --fov-up 15 --fov-down -15 --max-range 100 --overwrite >/dev/null
  $B run "$d" --out "$out/full-$1-$2" -q --threads 1 --config "$out/full.toml" >/dev/null
  $B run "$d" --out "$out/tiny-$1-$2" -q --threads 1 --set capacities=tiny --set runtime.scalar=f32 \
    --set runtime.map_storage=quantized >/dev/null
  python3 - "$out/full-$1-$2" "$out/tiny-$1-$2" "vlp16-$1-$2" <<'P'
import csv, json, sys
full, tiny, name = sys.argv[1:]
f = json.load(open(f"{full}/summary.json")); t = json.load(open(f"{tiny}/summary.json"))
fm, tm = f["metrics"], t["metrics"]
rows = list(csv.DictReader(open(f"{tiny}/frames.csv")))
drops = sum(1 for r in rows if any(int(r[k] or 0) for k in r if k.startswith("dropped_") and k != "dropped_non_finite"))
print(f"| {name} | {fm['ate_m']:.3f} / {fm['kitti_t_err_pct']:.3f} | {tm['ate_m']:.3f} / {tm['kitti_t_err_pct']:.3f} "
      f"| {tm['ate_m'] / fm['ate_m']:.2f} | {drops} of {len(rows)} | {t['state_bytes']} |")
P
done
