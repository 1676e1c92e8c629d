#!/usr/bin/env bash
# Degenerate scenes: kiss-odom reference mode, robust mode and GenZ-ICP 0.3.2 on the
# same generated runs and on kitti-mini (BENCHMARKS.md, "Degenerate scenes").
#
#   bench/degeneracy.sh [FRAMES] [SEEDS]     (default 500 frames, seeds "1 2 3")
#
# PROFILES picks the runs (default "corridor plane tunnel field urban fast kitti"; `kitti` is
# every kitti-mini sequence). GenZ-ICP runs its `corridor` preset on corridor, plane and tunnel,
# `outdoor` on field, urban and fast, `kitti` (no deskew) on kitti-mini; robust mode runs with
# its vehicle prior everywhere (--lateral-prior 1: every run is a car's) and its tunnel setting
# where GenZ-ICP has its corridor preset: every frame with plane terms, r_max / 200 voxels and
# the hold prior (--plane-gate 1 --voxel-size 0.5 --prediction-prior 0.01).
#
# Writes $OUT/results.jsonl (one line per run and system, with the estimated over the true
# distance travelled) and prints the Markdown table
# (bench/degeneracy_table.py). GenZ-ICP runs from a venv made here (target/genzvenv).
# Every system runs on one thread; run it alone at `nice` on a shared machine. REUSE_GENZ=1
# re-runs only kiss-odom, keeping GenZ-ICP's poses of an earlier run in the same $OUT.
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-500}
SEEDS=${2:-"1 2 3"}
PROFILES=${PROFILES:-"corridor plane tunnel field urban fast kitti"}
GEN=${GEN:-/work/data-gen/degeneracy}
OUT=${OUT:-$GEN/results-$FRAMES}
KITTI=${KISS_ODOM_KITTI_MINI:-../shared/data/kitti-mini}
GENZ=${GENZ_VENV:-target/genzvenv}
BIN=${BIN:-target/release/kiss-odom}
[ -x "$BIN" ] || cargo build --release -q -p kiss-odom
# genz-icp reads its presets' YAML files with PyYAML, which only its heavy `[all]` extra
# (open3d, polyscope, ouster-sdk...) brings: install it beside the package instead.
if ! "$GENZ/bin/python" -c "import genz_icp, yaml" 2>/dev/null; then
  [ -x "$GENZ/bin/python" ] || python3 -m venv "$GENZ"
  "$GENZ/bin/pip" install -q genz-icp==0.3.2 PyYAML==6.0.4
fi
mkdir -p "$OUT"
: > "$OUT/results.jsonl"

# record NAME SYSTEM POSES GT SECONDS_OR_HZ_JSON
record() {
  local m
  m=$("$BIN" eval "$3" "$4" --json)
  python3 - "$1" "$2" "$5" "$m" "$3" "$4" >> "$OUT/results.jsonl" <<'PY'
import json, math, sys
name, system, extra, metrics, poses, gt = sys.argv[1:]
def path(f):  # length of the path through the positions of a KITTI pose file
    p = [[float(v) for v in line.split()][3::4] for line in open(f) if line.strip()]
    return sum(math.dist(a, b) for a, b in zip(p, p[1:]))
row = {"run": name, "system": system, **json.loads(extra), **json.loads(metrics)}
row["path_ratio"] = path(poses) / path(gt) if path(gt) > 0 else None
print(json.dumps(row))
PY
}

ours() {  # ours NAME DATA MODE [ARGS]
  local o=$OUT/$1-$3
  "$BIN" run "$2" --threads 1 --quiet --degeneracy "$3" --out "$o" "${@:4}" >/dev/null
  local gt
  gt=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['input']['ground_truth'])" "$o/summary.json")
  record "$1" "$3" "$o/poses_kitti.txt" "$gt" \
    "$(python3 -c "import json,sys; s=json.load(open(sys.argv[1])); d=s['degraded_frames']; print(json.dumps({'hz': s['hz'], 'held_frames': d.get('held', 0), 'plane_frames': d.get('planes', 0)}))" "$o/summary.json")"
}

genz() {  # genz NAME DATA PRESET GT [ARGS]
  local o=$OUT/$1-genz.txt
  local info
  if [ -n "${REUSE_GENZ:-}" ] && [ -f "$o.json" ]; then
    info=$(cat "$o.json")  # GenZ-ICP's poses do not depend on kiss-odom: keep an earlier run's
  else
    info=$("$GENZ/bin/python" bench/genz_run.py "$2" "$o" --preset "$3" "${@:5}")
    echo "$info" > "$o.json"
  fi
  record "$1" "genz-$3" "$o" "$4" \
    "$(python3 -c "import json,sys; j=json.loads(sys.argv[1]); print(json.dumps({'hz': j['frames'] / j['seconds']}))" "$info")"
}

for p in $PROFILES; do
  case $p in
    kitti) continue ;;
    corridor | plane | tunnel)
      preset=corridor fine=(--lateral-prior 1 --plane-gate 1 --voxel-size 0.5 --prediction-prior 0.01) ;;
    *) preset=outdoor fine=(--lateral-prior 1) ;;
  esac
  for s in $SEEDS; do
    d=$GEN/$p-$FRAMES-s$s
    [ -f "$d/poses.txt" ] || "$BIN" simulate --out "$d" --frames "$FRAMES" --seed "$s" --profile "$p" >/dev/null
    name=$p-s$s
    echo "== $name" >&2
    ours "$name" "$d" reference
    ours "$name" "$d" robust "${fine[@]}"
    genz "$name" "$d" "$preset" "$d/poses.txt"
  done
done
for sq in $( [[ " $PROFILES " == *" kitti "* ]] && ls "$KITTI/sequences"); do
  d=$KITTI/sequences/$sq
  name=kitti-$sq
  echo "== $name" >&2
  ours "$name" "$d" reference
  ours "$name" "$d" robust --lateral-prior 1
  gt=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['input']['ground_truth'])" "$OUT/$name-reference/summary.json")
  genz "$name" "$d" kitti "$gt" --no-deskew
done
python3 bench/degeneracy_table.py "$OUT/results.jsonl"
