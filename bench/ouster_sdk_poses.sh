#!/usr/bin/env bash
# Reproduces the note on ouster-sdk's poses file in BENCHMARKS.md section 7, "From recordings
# and the network": which odometry made the poses file beside the OS-1-128 recording, and at
# which instant of the sweep its poses are (see bench/ouster_sdk_poses.py).
#
#   bash bench/ouster_sdk_poses.sh
#
# Makes target/kiss0210venv (kiss-icp 0.2.10 and numpy < 2, which its compiled module needs)
# and uses target/sensorvenv (ouster-sdk 1.0.1, made from tests/sensors/requirements.txt as
# .ci/run makes it) or KISS_ODOM_SENSOR_PYTHON.
set -euo pipefail
cd "$(dirname "$0")/.."
SENSOR_PY=${KISS_ODOM_SENSOR_PYTHON:-target/sensorvenv/bin/python}
VENV=target/kiss0210venv
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q "kiss-icp==0.2.10" "numpy<2"
fi
mkdir -p target/bench/ouster-sdk-poses
npz=target/bench/ouster-sdk-poses/points.npz
"$SENSOR_PY" bench/ouster_sdk_poses.py export "$npz"
"$VENV/bin/python" bench/ouster_sdk_poses.py run "$npz"
