#!/usr/bin/env bash
# which odometry made ouster-sdk's poses file beside the OS-1-128 recording, and at
# which instant of the sweep its poses are (see bench/ouster_sdk_poses.py). Makes
# target/kiss0210venv (kiss-icp 0.2.10 and numpy < 2, which its compiled module needs) and uses
# target/sensorvenv (ouster-sdk 1.0.1, made by .ci/run) or KISS_ODOM_SENSOR_PYTHON.
set -euo pipefail
cd "$(dirname "$0")/.."
SENSOR_PY=${KISS_ODOM_SENSOR_PYTHON:-target/sensorvenv/bin/python}
VENV=target/kiss0210venv
if [ ! -x "$VENV/bin/python" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q "kiss-icp==0.2.10" "numpy<2"
fi
npz=$(mktemp --suffix .npz)
trap 'rm -f "$npz"' EXIT
"$SENSOR_PY" bench/ouster_sdk_poses.py export "$npz"
"$VENV/bin/python" bench/ouster_sdk_poses.py run "$npz"
