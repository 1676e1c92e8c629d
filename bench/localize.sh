#!/usr/bin/env bash
# Localization in a prior map on generated revisit runs (BENCHMARKS.md, "Localization in a prior
# map"). For each profile and seed, the first run's ground truth builds the map (`map build`),
# and the revisit (the same scene driven the other way in the next lane, 10 % of its objects
# changed, a new wall) is localized in it (`run --map`) and run as odometry alone from the same
# start. On seed 1 of each profile also: a start 5 m and 20 degrees off the given pose, a map of
# the first run's second half only (the revisit drives out of it), and 30 % of the objects
# changed. One JSON line per run (bench/localize_score.py): position errors of both, frames by
# state, `lost` against an error over 1 m both ways, confident wrong frames.
#
#   bash bench/localize.sh [FRAMES] [SEEDS] [PROFILES]    (default: 500 "1 2 3" "urban warehouse field")
#
# DATA: where the generated runs go (default target/bench/localize; about 0.7 GB a run).
# EXTRAS=0 leaves out the kidnapped, uncovered and changed runs. The speed figure, after a run:
#   farm-bench --vs "sh -c 'exec kiss-odom run DATA/urban-1-B --threads 1 --quiet --out O1'" \
#     -- sh -c "exec kiss-odom run DATA/urban-1-B --map DATA/out/urban-1/map.komap \
#     --initial-pose $(cat DATA/urban-1-B/initial_pose.txt) --threads 1 --quiet --out O2"
# The open field runs (map and both runs) with `--preset accurate`: the default odometry is
# hundreds of metres off there (BENCHMARKS.md section 15), and localization predicts with it.
set -euo pipefail
FRAMES=${1:-500}
SEEDS=${2:-1 2 3}
PROFILES=${3:-urban warehouse field}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DATA=${DATA:-$ROOT/target/bench/localize}
BIN=${BIN:-$ROOT/target/release/kiss-odom}
[ -n "${BIN_BUILT:-}" ] || cargo build --release -q -p kiss-odom --manifest-path "$ROOT/Cargo.toml"
mkdir -p "$DATA"

sim() { # NAME ARGS...: a generated run, once
  local dir=$DATA/$1
  shift
  [ -d "$dir" ] || "$BIN" simulate --frames "$FRAMES" "$@" --out "$dir" >/dev/null
}

# The revisit's start, moved 3 m in x, 4 m in y and 20 degrees in yaw.
off() {
  python3 -c "import sys; v=[float(x) for x in open(sys.argv[1]).read().split(',')];
v[0]+=3; v[1]+=4; v[5]+=20; print(','.join(repr(x) for x in v))" "$1"
}

case_() { # NAME A B FROM START: map from A's frames FROM.., B localized from START, and B alone
  local name=$1 a=$DATA/$2 b=$DATA/$3 start=$5 out=$DATA/out/$1 preset=()
  [[ $name != field* ]] || preset=(--preset accurate)
  mkdir -p "$out"
  tail -n +"$(($4 + 1))" "$a/poses.txt" >"$out/map_poses.txt"
  "$BIN" map build "$a" --frames "$4.." --poses "$out/map_poses.txt" "${preset[@]}" \
    --out "$out/map.komap" >/dev/null
  local t0 t1 t2
  t0=$(date +%s.%N)
  "$BIN" run "$b" --map "$out/map.komap" --initial-pose "$start" "${preset[@]}" \
    --out "$out/loc" --quiet --threads 1
  t1=$(date +%s.%N)
  "$BIN" run "$b" "${preset[@]}" --out "$out/odo" --quiet --threads 1
  t2=$(date +%s.%N)
  python3 "$ROOT/bench/localize_score.py" "$name" "$b/poses.txt" "$b/initial_pose.txt" \
    "$out/loc" "$out/odo" "$(echo "$t1 - $t0" | bc)" "$(echo "$t2 - $t1" | bc)"
}

for p in $PROFILES; do
  for s in $SEEDS; do
    sim "$p-$s-A" --profile "$p" --seed "$s"
    sim "$p-$s-B" --profile "$p" --seed "$s" --revisit
    case_ "$p-$s" "$p-$s-A" "$p-$s-B" 0 "$(cat "$DATA/$p-$s-B/initial_pose.txt")"
  done
  [ "${EXTRAS:-1}" = 1 ] || continue
  s=${SEEDS%% *}
  case_ "$p-$s-kidnapped" "$p-$s-A" "$p-$s-B" 0 "$(off "$DATA/$p-$s-B/initial_pose.txt")"
  case_ "$p-$s-uncovered" "$p-$s-A" "$p-$s-B" $((FRAMES / 2)) \
    "$(cat "$DATA/$p-$s-B/initial_pose.txt")"
  sim "$p-$s-B30" --profile "$p" --seed "$s" --revisit --changes 0.3
  case_ "$p-$s-changed30" "$p-$s-A" "$p-$s-B30" 0 "$(cat "$DATA/$p-$s-B30/initial_pose.txt")"
done
