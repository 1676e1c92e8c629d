#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 14, "Against LiDAR only and LiDAR-inertial peers" (our
# rows) and the variants of its "Tried and dropped: gyroscope prior": the gyroscope prior
# (`run --imu auto`) against the LiDAR-only reference on generated
# hand-held and drone runs with an IMU (`simulate --imu-rate 200`: noise, turn-on biases that
# walk), deskew on, seeds 1-3: drone 500 frames, hand-held 1,000 (KITTI's 100 m segments need
# that at walking pace). Variants: each point deskewed with the gyroscope's rotation to its time
# (the prior) or the sweep at the rotation's mean rate, the bias gain (0.1 default, 0.02, 0: no
# bias estimate) and the prior without deskewing. Prints a markdown table: KITTI relative
# translation error, ATE, mean relative rotation error per frame.
#
#   bench/imu_prior.sh     (DATA=target/bench/imu, SEEDS="1 2 3", BIN=a kiss-odom to use;
#                           drives kept for reruns; about 40 min)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${BIN:-target/release/kiss-odom}
[ -n "${BIN:-}" ] || cargo build --release -q -p kiss-odom
DATA=${DATA:-target/bench/imu}; mkdir -p "$DATA"
rows="$DATA/rows.tsv"; : > "$rows"
printf '[imu]\nbias_gain = 0.02\n' > "$DATA/g002.toml"
printf '[imu]\nbias_gain = 0.0\n' > "$DATA/g0.toml"
printf '[imu]\npoint_deskew = false\n' > "$DATA/mean.toml"
for spec in "drone 500" "handheld 1000"; do
  set -- $spec
  for seed in ${SEEDS:-1 2 3}; do
    d="$DATA/$1-$seed"
    [ -f "$d/imu.csv" ] || $B simulate --out "$d" --frames "$2" --seed "$seed" --profile "$1" \
      --imu-rate 200 --overwrite >/dev/null
    for variant in "off:" "prior:--imu auto" "mean rate:--imu auto --config $DATA/mean.toml" \
                   "gain 0.02:--imu auto --config $DATA/g002.toml" \
                   "gain 0:--imu auto --config $DATA/g0.toml" "prior, no deskew:--imu auto --set data.deskew=false"; do
      name=${variant%%:*}; args=${variant#*:}
      out="$d.${name// /_}"; out=${out//,/}
      # shellcheck disable=SC2086
      $B run "$d" --set data.deskew=true $args --out "$out" -q 2>/dev/null >/dev/null
      printf '%s\t%s\t%s\t%s\n' "$1" "$seed" "$name" "$(tr -d '\n ' < "$out/summary.json")" >> "$rows"
    done
  done
done
python3 - "$rows" <<'P'
import json, sys
from collections import defaultdict
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print("| run | seed | variant | KITTI % | ATE m | RPE rad/frame | frames/s |")
print("|---|---|---|---|---|---|---|")
means = defaultdict(list)
for prof, seed, name, s in rows:
    s = json.loads(s)
    m = s["metrics"]
    means[(prof, name)].append((m["kitti_t_err_pct"], m["ate_m"], m["rpe_rad_mean"]))
    print(f"| {prof} | {seed} | {name} | {m['kitti_t_err_pct']:.3f} | {m['ate_m']:.3f} | "
          f"{m['rpe_rad_mean']:.4f} | {s['hz']:.1f} |")
for (prof, name), v in means.items():
    k, a, r = (sum(x[i] for x in v) / len(v) for i in range(3))
    print(f"| **{prof}, mean of {len(v)}** | | {name} | {k:.3f} | {a:.3f} | {r:.4f} | |")
P
