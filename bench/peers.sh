# Shared by bench/degeneracy.sh, bench/accurate.sh and bench/spread.sh (BENCHMARKS.md sections
# 12 and 15; sourced, not run, from the repository's root): the peers' venvs, running each system on a folder and recording its scores as one JSON
# line in $OUT/results.jsonl. Needs OUT; BIN (kiss-odom, built when missing), GENZ and MAD (the
# peers' venvs) and KITTI (kitti-mini) have defaults.
BIN=${BIN:-target/release/kiss-odom}
GENZ=${GENZ_VENV:-target/genzvenv}
MAD=${MAD_VENV:-target/madvenv}
KITTI=${KISS_ODOM_KITTI_MINI:-../shared/data/kitti-mini}
[ -x "$BIN" ] || cargo build --release -q -p kiss-odom

# GenZ-ICP 0.3.2. It reads its presets' YAML files with PyYAML, which only its heavy `[all]`
# extra (open3d, polyscope, ouster-sdk...) brings: installed beside the package instead.
genz_venv() {
  if ! "$GENZ/bin/python" -c "import genz_icp, yaml" 2>/dev/null; then
    [ -x "$GENZ/bin/python" ] || python3 -m venv "$GENZ"
    "$GENZ/bin/pip" install -q genz-icp==0.3.2 PyYAML==6.0.4
  fi
}

# MAD-ICP 0.0.10 is an sdist only: its C++ core is built here. Its build asks for
# scikit-build-core's old `cmake.verbose` key (refused from 0.10 on) and Eigen 3.4 (fetched from
# gitlab.com when missing, which this network does not reach: Debian's libeigen3-dev instead).
# Its runtime dependencies are those its KITTI reader imports; open3d, rosbags and typer (its
# viewer and bag readers) are left out.
mad_venv() {
  "$MAD/bin/python" -c "import mad_icp.src.pybind.pypeline" 2>/dev/null && return 0
  [ -f /usr/include/eigen3/Eigen/Core ] ||
    { apt-get install -y -q libeigen3-dev || { apt-get update -q && apt-get install -y -q libeigen3-dev; }; } >/dev/null
  [ -x "$MAD/bin/python" ] || python3 -m venv "$MAD"
  "$MAD/bin/pip" install -q "scikit-build-core<0.10" pybind11==2.13.6 cmake ninja numpy \
    natsort==8.4.0 scipy PyYAML
  CMAKE_BUILD_PARALLEL_LEVEL=2 "$MAD/bin/pip" install -q --no-build-isolation --no-deps mad-icp==0.0.10
}

# record NAME SYSTEM POSES GT EXTRA_JSON: scores POSES against GT, with the distance travelled
# estimated over the true one.
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

# ours NAME DATA SYSTEM [ARGS]: kiss-odom on one thread with ARGS; prints the ground truth.
ours() {
  local o=$OUT/$1-$3
  "$BIN" run "$2" --threads 1 --quiet --out "$o" "${@:4}" >/dev/null
  local gt
  gt=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['input']['ground_truth'])" "$o/summary.json")
  record "$1" "$3" "$o/poses_kitti.txt" "$gt" \
    "$(python3 -c "import json,sys; s=json.load(open(sys.argv[1])); d=s['degraded_frames']; print(json.dumps({'hz': s['hz'], 'plane_frames': d.get('planes', 0)}))" "$o/summary.json")" >/dev/null
  echo "$gt"
}

# peer NAME SYSTEM GT COMMAND...: a peer's run (its poses to $OUT/NAME-SYSTEM.txt, which
# COMMAND gets as its last argument), kept with REUSE_PEERS=1 when an earlier run left them;
# with PEERS=0 only such kept runs are recorded (the peers run elsewhere).
peer() {
  local o=$OUT/$1-$2.txt info
  if [ "${PEERS:-1}" = 0 ] && [ ! -f "$o.json" ]; then
    return 0
  fi
  if [ -n "${REUSE_PEERS:-}" ] && [ -f "$o.json" ]; then
    info=$(cat "$o.json")  # a peer's poses do not depend on kiss-odom: keep an earlier run's
  else
    info=$("${@:4}" "$o")
    echo "$info" > "$o.json"
  fi
  record "$1" "$2" "$o" "$3" \
    "$(python3 -c "import json,sys; j=json.loads(sys.argv[1]); print(json.dumps({'hz': j['frames'] / j['seconds']}))" "$info")" >/dev/null
}

# genz NAME DATA PRESET GT [ARGS]: GenZ-ICP with one of its presets.
genz() {
  peer "$1" "genz-$3" "$4" "$GENZ/bin/python" bench/genz_run.py "${@:5}" --preset "$3" "$2"
}

# mad NAME DATA GT [ARGS]: MAD-ICP with its default parameters.
mad() {
  peer "$1" mad "$3" "$MAD/bin/python" bench/mad_run.py "${@:4}" "$2"
}
