#!/usr/bin/env bash
# The wheels in dist/ (python/build-wheels.sh) installed as a user installs them, with no Rust
# toolchain anywhere on PATH, and tested.
#
# Usage: bash python/test-wheels.sh x86_64 [PYTEST ARGS...]
#        bash python/test-wheels.sh aarch64
#
# x86_64: into a venv (target/wheeltest, or VENV=...), with python/tests/requirements.txt; then
#   python/tests whole (pytest arguments may narrow it).
# aarch64: under qemu-user on this machine. A Debian 12 arm64 root (debootstrap's first stage,
#   its packages unpacked: CPython 3.11 and the C libraries) in target/arm64/root; numpy,
#   kiss-icp 1.3.0 (its own aarch64 wheel), pytest and the wheel installed into
#   target/arm64/site by pip for the aarch64 platform, binary wheels only (with PyYAML, which
#   the configuration tests read kiss-icp's YAML with). Then the drop-in
#   tests (python/tests/test_kissicp.py: poses equal to `kiss-odom run`'s, within 1e-9 m of
#   kiss-icp's, on kitti-mini) and python/bench/fps.py (frames/s against kiss-icp, both
#   emulated). Needs qemu-user-static and debootstrap (installed by apt-get when missing).
#
# Environment: KISS_ODOM_BIN (the x86_64 `kiss-odom`, default target/release/kiss-odom-cli),
# KISS_ODOM_DATA (default ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$PWD
arch=${1:?usage: test-wheels.sh x86_64|aarch64 [PYTEST ARGS...]}
shift
export KISS_ODOM_BIN="${KISS_ODOM_BIN:-$REPO/target/release/kiss-odom-cli}"
export KISS_ODOM_DATA="${KISS_ODOM_DATA:-$REPO/../shared/data}"
wheel=$(ls dist/kiss_odom-*-manylinux*"$arch".whl)

# PATH without a Rust toolchain: rustup's and cargo's folders out, then checked.
NO_RUST_PATH=$(tr ':' '\n' <<<"$PATH" | grep -v -e '\.cargo' -e '\.rustup' | paste -sd:)
if PATH=$NO_RUST_PATH command -v cargo rustc >/dev/null; then
  echo "FAILED: a Rust toolchain is still on PATH: $(PATH=$NO_RUST_PATH command -v cargo rustc)" >&2
  exit 1
fi

case $arch in
x86_64)
  VENV=${VENV:-target/wheeltest}
  [ -x "$VENV/bin/pip" ] || python3 -m venv "$VENV"
  PATH=$NO_RUST_PATH "$VENV/bin/pip" install --quiet -r python/tests/requirements.txt
  PATH=$NO_RUST_PATH "$VENV/bin/pip" install --quiet --only-binary :all: --force-reinstall \
    --no-deps "$wheel"
  # From outside the source tree: the installed package, not python/kiss_odom.
  cd /tmp
  PATH=$NO_RUST_PATH "$REPO/$VENV/bin/python" -m pytest -q -p no:cacheprovider \
    "$REPO/python/tests" "$@"
  ;;
aarch64)
  ROOT=target/arm64/root SITE=target/arm64/site
  if ! command -v qemu-aarch64-static debootstrap >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q qemu-user-static debootstrap >/dev/null
  fi
  if ! [ -x "$ROOT/usr/bin/python3.11" ]; then
    rm -rf "$ROOT" && mkdir -p "$ROOT"
    debootstrap --arch=arm64 --foreign --variant=minbase --include=python3 bookworm "$ROOT" \
      http://deb.debian.org/debian >/dev/null
    for deb in "$ROOT"/var/cache/apt/archives/*.deb; do dpkg-deb -x "$deb" "$ROOT"; done
  fi
  rm -rf "$SITE"
  PATH=$NO_RUST_PATH python3 -m pip install --quiet --no-warn-conflicts --target "$SITE" \
    --platform manylinux_2_17_aarch64 --platform manylinux2014_aarch64 --python-version 3.11 \
    --implementation cp --only-binary :all: numpy==2.2.6 kiss-icp==1.3.0 pyyaml==6.0.3 pytest==9.2.0 \
    "$wheel"
  py() { PATH=$NO_RUST_PATH PYTHONPATH="$REPO/$SITE" \
    qemu-aarch64-static -L "$REPO/$ROOT" "$REPO/$ROOT/usr/bin/python3.11" "$@"; }
  cd /tmp
  py -c "import platform, kiss_odom, kiss_icp.kiss_icp; print('emulated', platform.machine(), \
'python', platform.python_version(), 'kiss_odom from', kiss_odom.__file__)"
  SECONDS=0
  out=$(py -m pytest -q -s -p no:cacheprovider -rs "$REPO/python/tests/test_kissicp.py" 2>&1) ||
    { echo "$out"; exit 1; }
  echo "$out" | grep -E "differ|worst|passed|failed|skipped"
  # A skip here (kiss-icp or the data missing) would prove nothing.
  if grep -q "skipped" <<<"$out"; then echo "FAILED: tests skipped under emulation" >&2; exit 1; fi
  echo "drop-in tests under qemu-aarch64: $SECONDS s"
  py "$REPO/python/bench/fps.py" --repeats 1 --kitti "$KISS_ODOM_DATA/kitti-mini/sequences"
  ;;
*)
  echo "unknown architecture: $arch" >&2
  exit 2
  ;;
esac
