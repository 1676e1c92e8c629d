#!/usr/bin/env bash
# The dataset-layout tests (`layouts::` of the workspace tests) with every loader's own reading
# library, which CI leaves out for their size: open3d (Apollo's PCD, 0.9 GB installed),
# pyntcloud (Newer College's PCD; it needs numpy below 2) and nuscenes-devkit (nuScenes'
# tables; numpy below 2, with OpenCV, matplotlib, scikit-learn and Shapely). CI runs the same
# tests with the stand-ins of tests/reference/standins/ in their place.
#
#   bench/layouts.sh
#
# Makes two venvs (once; a few minutes and about 3 GB): target/layoutsvenv (kiss-icp 1.3.0,
# numpy 2, scipy, open3d) for KISS_ODOM_PYTHON and target/layoutsnp1venv (the same with numpy
# 1.26, pyntcloud and nuscenes-devkit) for KISS_ODOM_NUMPY1_PYTHON, then runs the tests. Each
# layout prints "(with a stand-in for ...)" where a stand-in was used: here, none should be.
# On Debian, open3d also needs the libusb-1.0-0 package.
set -euo pipefail
cd "$(dirname "$0")/.."
venv() { # venv DIR IMPORTS REQUIREMENTS...
  local dir=$1 imports=$2
  shift 2
  if "$dir/bin/python" -c "import $imports" 2>/dev/null; then return 0; fi
  python3 -m venv "$dir" && "$dir/bin/pip" install --quiet "$@"
}
venv target/layoutsvenv "kiss_icp, scipy, open3d" -r tests/reference/requirements.txt \
  -r tests/reference/requirements-layouts.txt open3d==0.20.0
venv target/layoutsnp1venv "kiss_icp, scipy, pyntcloud, nuscenes" kiss-icp==1.3.0 \
  numpy==1.26.4 scipy==1.17.1 pandas==2.3.3 pyntcloud==0.3.1 nuscenes-devkit==1.2.0
KISS_ODOM_PYTHON="$PWD/target/layoutsvenv/bin/python" \
  KISS_ODOM_NUMPY1_PYTHON="$PWD/target/layoutsnp1venv/bin/python" \
  nice -n 10 cargo test --release -p kiss-odom-tests --test workspace layouts:: -- --nocapture
