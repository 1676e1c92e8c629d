#!/usr/bin/env bash
# Reproduces BENCHMARKS.md section 8, "Speed against kiss-icp's KissICP" (`fps`) and "Batch on
# Ray" (`batch`), with the `kiss_odom` package built from this tree.
#
#   bash bench/python.sh fps      # python/bench/fps.py: kitti-mini and a generated drive, 7 repeats
#   bash bench/python.sh batch    # kiss-odom-batch over seven folders, one of them corrupt
#   bash bench/python.sh venv     # only make the venv (bench/accurate_fps.sh uses it)
#
# The venv (PY, default target/pyvenv) is made when missing: python/tests/requirements.txt
# (kiss-icp 1.3.0, numpy, evo, Ray), then `pip install ./python` (maturin builds the extension:
# several minutes). Generated data goes to target/bench/python.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-target/pyvenv}
D=target/bench/python
step=${1:?fps, batch or venv}

if ! "$PY/bin/python" -c "import kiss_odom, kiss_icp" 2>/dev/null; then
  [ -x "$PY/bin/python" ] || python3 -m venv "$PY"
  "$PY/bin/pip" install -q -r python/tests/requirements.txt
  "$PY/bin/pip" install -q ./python
fi
[ "$step" = venv ] && exit 0
cargo build --release -q -p kiss-odom
B=$PWD/${CARGO_TARGET_DIR:-target}/release/kiss-odom
mkdir -p "$D"

case $step in
  fps)
    # One thread each, frames preloaded as numpy arrays; the script checks both sides' poses
    # agree (1e-9 m), so the timed work is the same.
    [ -f "$D/urban/poses.txt" ] || "$B" simulate --out "$D/urban" --frames 100 >/dev/null
    "$PY/bin/python" python/bench/fps.py --repeats "${REPEATS:-7}" --generated "$D/urban"
    ;;
  batch)
    b=$D/batch
    mkdir -p "$b" && rm -rf "$b/out"
    [ -f "$b/fast-s1/poses.txt" ] || "$B" simulate --out "$b/fast-s1" --frames 90 --seed 1 \
      --profile fast --beams 32 --columns 512 >/dev/null
    [ -f "$b/corridor-s3/poses.txt" ] || "$B" simulate --out "$b/corridor-s3" --frames 20 \
      --seed 3 --profile corridor --beams 32 --columns 512 >/dev/null
    printf '\x89MCAP0\r\ngarbage' > "$b/corrupt.mcap"
    S=../shared/data/kitti-mini/sequences
    start=$(date +%s.%N)
    status=0
    KISS_ODOM_BIN=$B "$PY/bin/kiss-odom-batch" "$S/01" "$S/02" "$S/04" "$S/05" "$b/fast-s1" \
      "$b/corridor-s3" "$b/corrupt.mcap" --out "$b/out" --num-cpus 2 -- --threads 1 || status=$?
    echo "wall $(python3 -c "print(f'{$(date +%s.%N) - $start:.1f}')") s, exit status $status"
    ;;
  *) echo "unknown step $step: fps, batch or venv" >&2; exit 2 ;;
esac
