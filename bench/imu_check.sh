#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 14, "A wrong IMU": on
# generated drone and hand-held runs (`simulate --imu-rate 200`, 150 frames, deskew on, seeds
# 1-3) the IMU replaced by a wrong but plausible one (bench/imu_wrong.py: rates in deg/s, the x
# or z axis flipped, a dead gyroscope, one 1e6 rad/s sample, another seed's imu.csv, each sample
# doubled with another seed's rates), the right one with its extrinsic turned by 180 degrees,
# and the deg/s one under `--preset accurate` (against that preset's `--imu off`); and, as the
# noise those ratios are read against, the right IMU for the first 0.15, 0.25 or 0.45 s only
# (a run that differs from `--imu off`'s in its first frames alone). Prints a
# markdown table, per IMU over the seeds: the first frame rejected, runs that warned, runs whose
# warning named the cause the IMU was made wrong by (none for another flight's), ATE over
# `--imu off`'s. Exit 1 (naming the run) when a wrong IMU is not rejected within the first
# second (frame 10; the corrupt sample is left out instead), does not warn or ends more than
# 10 % above `--imu off`'s ATE, or the right IMU is rejected on any frame or warned about.
#
#   bench/imu_check.sh     (DATA=target/bench/imu-check, SEEDS="1 2 3", BIN=a kiss-odom to
#                           use; drives kept for reruns; about 20 min)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${BIN:-target/release/kiss-odom}
[ -n "${BIN:-}" ] || cargo build --release -q -p kiss-odom
DATA=${DATA:-target/bench/imu-check}; mkdir -p "$DATA"
SEEDS=${SEEDS:-1 2 3}
rows="$DATA/rows.tsv"; : > "$rows"
cause() { # cause ERR: the cause the warning in ERR names, as a variant's name
  local e
  e=$(grep -m1 'gyroscope prior' "$1" || true)
  case $e in
  "") echo - ;; *57.3*) echo degs ;; *"corrupt sample"*) echo spike ;; *"dead gyroscope"*) echo dead ;;
  *"180 degrees about x"*) echo ext180 ;; *"180 degrees about"*) echo rotated ;;
  *"x axis (LiDAR"*) echo flipx ;; *"y axis (LiDAR"*) echo flipy ;; *"z axis (LiDAR"*) echo flipz ;;
  *) echo unknown ;;
  esac
}
run() { # run DATA DRIVE NAME ARGS...: one run of DATA, its row under DRIVE's name
  local data=$1 d=$2 name=$3; shift 3
  local out="$d.$name"
  rm -rf "$out"
  $B run "$data" --set data.deskew=true "$@" --out "$out" -q 2>"$out.err" >/dev/null || true
  local first rejected
  first=$(python3 -c "import csv,sys; r=[x['imu_prior'] for x in csv.DictReader(open('$out/frames.csv'))] if '$name' not in ('off','acc_off') else []; print(next((k for k,v in enumerate(r) if v=='rejected'), -1))")
  rejected=$(python3 -c "import json; print(json.load(open('$out/summary.json')).get('imu_rejected_frames', 0))")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "${d##*/}" "$name" "$first" "$rejected" \
    "$(grep -c 'gyroscope prior' "$out.err" || true)" \
    "$(python3 -c "import json; print(json.load(open('$out/summary.json'))['metrics']['ate_m'])")" \
    "$(cause "$out.err")" >> "$rows"
}
for prof in drone handheld; do
  for seed in $SEEDS; do
    d="$DATA/$prof-$seed"
    [ -f "$d/imu.csv" ] || $B simulate --out "$d" --frames 150 --seed "$seed" --profile "$prof" \
      --imu-rate 200 --overwrite >/dev/null
  done
  for seed in $SEEDS; do
    d="$DATA/$prof-$seed"
    other="$DATA/$prof-$(( seed % 3 + 1 ))"
    [ -f "$other/imu.csv" ] || $B simulate --out "$other" --frames 150 --seed "$(( seed % 3 + 1 ))" \
      --profile "$prof" --imu-rate 200 --overwrite >/dev/null
    run "$d" "$d" off
    run "$d" "$d" right --imu auto
    run "$d" "$d" ext180 --imu auto --set "imu.extrinsic=[0,0,0,180,0,0]"
    run "$d" "$d" acc_off --preset accurate
    # The right IMU for the first frames only, then none: how far --imu off's ATE moves when
    # only its first frames change (the noise a wrong IMU's ratio is read against).
    for v in stop0.15 stop0.25 stop0.45; do
      python3 bench/imu_wrong.py "$d" "$v" "$d.$v-data"
      run "$d.$v-data" "$d" "$v" --imu auto
    done
    for v in degs flipx flipz dead spike other dup; do
      python3 bench/imu_wrong.py "$d" "$v" "$d.$v-data" "$other"
      run "$d.$v-data" "$d" "$v" --imu auto
      [ "$v" != degs ] || run "$d.$v-data" "$d" acc_degs --imu auto --preset accurate
    done
  done
done
python3 - "$rows" <<'P'
import sys
from collections import defaultdict
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
off = {(d, n): float(a) for d, n, f, r, w, a, c in rows if n in ("off", "acc_off")}
# The cause each wrong IMU should be named by (another flight's rates, or a mix, by none).
named = {"degs": "degs", "acc_degs": "degs", "flipx": "flipx", "flipz": "flipz", "dead": "dead",
         "spike": "spike", "other": "unknown", "dup": "unknown", "ext180": "ext180"}
label = {"right": "right IMU", "degs": "gyroscope in deg/s", "flipx": "x axis flipped",
         "flipz": "z axis flipped", "dead": "dead gyroscope (zeros)",
         "spike": "one sample of 1e6 rad/s", "other": "another flight's imu.csv",
         "dup": "each sample doubled with another flight's",
         "ext180": "extrinsic off by 180 deg (roll)", "acc_degs": "deg/s, `--preset accurate`",
         "stop": "right IMU for 0.15, 0.25 or 0.45 s, then none (noise)"}
runs, bad = defaultdict(list), []
for d, n, f, r, w, a, c in rows:
    if n in ("off", "acc_off"):
        continue
    ratio = float(a) / off[(d, "acc_off" if n.startswith("acc_") else "off")]
    if n.startswith("stop"):
        runs[("stop", d.rsplit("-", 1)[0])].append((-1, int(r), w != "0", ratio, False))
        continue
    runs[(n, d.rsplit("-", 1)[0])].append((int(f), int(r), w != "0", ratio, c == named.get(n)))
    # A corrupt sample is left out, not rejected: it warns, and the run keeps the prior.
    in_time = 0 <= int(f) <= 10 or (n == "spike" and int(f) < 0)
    ok = (int(r) == 0 and w == "0") if n == "right" else (in_time and w != "0" and ratio <= 1.1)
    if not ok:
        bad.append(f"{d} {n}: first rejected {f}, {r} rejected, warned {w != '0'}, ATE x{ratio:.2f}")
print("| IMU | drone: first frame rejected | warned | cause named | ATE / `--imu off` "
      "| hand-held: first frame rejected | warned | cause named | ATE / `--imu off` |")
print("|---|---|---|---|---|---|---|---|---|")
for n, name in label.items():
    cells = []
    for prof in ("drone", "handheld"):
        v = runs[(n, prof)]
        if not v:
            cells += ["", "", "", ""]
            continue
        first = f"never ({sum(x[1] for x in v)} frames)" if all(x[0] < 0 for x in v) else \
            f"{min(x[0] for x in v)}-{max(x[0] for x in v)}"
        cause = "" if n in ("right", "stop") else f"{sum(x[4] for x in v)}/{len(v)}"
        cells += [first, f"{sum(x[2] for x in v)}/{len(v)}", cause,
                  f"{min(x[3] for x in v):.2f}-{max(x[3] for x in v):.2f}"]
    print(f"| {name} | " + " | ".join(cells) + " |")
for b in bad:
    print("FAIL:", b)
sys.exit(1 if bad else 0)
P
