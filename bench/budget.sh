#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 10, "The work budget", both tables: what a per-frame work
# budget costs and buys. For each budget: accuracy on kitti-mini
# and on generated urban/fast drives (host, f32 + quantized map + SMALL capacities at 50 m, the
# microcontroller configuration; the same work units as on the target), the worst frame's work,
# and the Cortex-M7's instruction counts per frame under QEMU on the embedded kitti-mini 05
# frames (SMALL) and VLP-16 sweeps (TINY).
#
#   bench/budget.sh [budget...]        (default: none 400000 250000 150000 100000)
#
# DATA (default target/bench/budget) holds urban-7-1000 and fast-5-500 from
# `kiss-odom simulate --frames N --seed S --profile P`; made here if missing. The Cortex-M7 part
# needs QEMU and the Rust target (embedded/README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
budgets=("$@"); [ ${#budgets[@]} -gt 0 ] || budgets=(none 400000 250000 150000 100000)
cargo build --release -q -p kiss-odom
B=target/release/kiss-odom
DATA=${DATA:-target/bench/budget}; mkdir -p "$DATA"
for spec in "urban 7 1000" "fast 5 500"; do
  set -- $spec; d="$DATA/$1-$2-$3"
  [ -f "$d/sim.toml" ] || $B simulate --out "$d" --frames "$3" --seed "$2" --profile "$1" >/dev/null
done
out=$DATA/runs; mkdir -p "$out"
runs=(../shared/data/kitti-mini/sequences/01 ../shared/data/kitti-mini/sequences/02
      ../shared/data/kitti-mini/sequences/04 ../shared/data/kitti-mini/sequences/05
      "$DATA/urban-7-1000" "$DATA/fast-5-500")
echo "| budget | run | ATE m | KITTI t err % | frames stopped by the budget | worst frame work |"
echo "|---|---|---|---|---|---|"
for b in "${budgets[@]}"; do
  flag=(); [ "$b" = none ] || flag=(--set registration.work_budget="$b")
  for r in "${runs[@]}"; do
    o="$out/$b-$(basename "$r")"
    $B run "$r" --out "$o" -q --threads 1 --set capacities=small --set runtime.scalar=f32 --set runtime.map_storage=quantized \
      --max-range 50 --set mapping.voxel_size=1 "${flag[@]}" >/dev/null 2>&1 || true
    python3 - "$o" "$b" "$(basename "$r")" <<'P'
import csv, json, sys
o, b, r = sys.argv[1:]
s = json.load(open(f"{o}/summary.json")); m = s.get("metrics") or {}
rows = list(csv.DictReader(open(f"{o}/frames.csv")))
stopped = sum(1 for x in rows if x.get("budget") == "1")
worst = max(int(x["work"] or 0) for x in rows)
t = m.get("kitti_t_err_pct"); t = f"{t:.3f}" if t is not None else "-"
print(f"| {b} | {r} | {m.get('ate_m', float('nan')):.4f} | {t} | {stopped} of {len(rows)} | {worst} |")
P
  done
done
echo
echo "| budget | case | worst frame insns (M7, QEMU) | mean insns | est. worst ms at 600 MHz |"
echo "|---|---|---|---|---|"
for b in "${budgets[@]}"; do
  e=""; [ "$b" = none ] || e="$b"
  for c in "m7:" "m7:tiny"; do
    KISS_EMBED_BUDGET="$e" KISS_FEATURES="${c#*:}" bash embedded/run.sh "${c%%:*}" 2>/dev/null \
      > "$out/m7-${c#*:}-$b.txt" || true
    awk -v b="$b" -v c="${c#*:}" '/^cost [1-9]/ { split($3, a, "="); n++; s += a[2]; if (a[2] > w) w = a[2] }
      END { printf "| %s | %s | %.1f M | %.1f M | %.0f |\n", b, (c == "" ? "small, kitti-mini 05" : "tiny, VLP-16"), w/1e6, s/n/1e6, w/600e3 }' \
      "$out/m7-${c#*:}-$b.txt"
  done
done
