#!/usr/bin/env bash
# The kiss-odom Python package as users install it: one abi3 wheel (CPython 3.9 and later) per
# architecture, for manylinux x86_64 and aarch64, and an sdist, into dist/.
#
# Usage: bash python/build-wheels.sh [ARCH...]      ARCH: x86_64, aarch64 (default: both)
#
# The wheels are cross-linked by zig (maturin --zig, ziglang from PyPI) against glibc 2.17, the
# manylinux2014 floor: no Docker image, no cross gcc, and the same route for both
# architectures. Each wheel is then checked by auditwheel: its platform tag, and no shared
# library it needs beyond the manylinux set (libc, libm, libgcc_s, libpthread, libdl).
# Installs what it needs itself: the build venv in target/wheelvenv and the Rust target by rustup.
set -euo pipefail
cd "$(dirname "$0")/.."
ARCHES=("$@")
[ ${#ARCHES[@]} -gt 0 ] || ARCHES=(x86_64 aarch64)
MANYLINUX=manylinux_2_17 # glibc 2.17

VENV=target/wheelvenv
if ! "$VENV/bin/python" -c "import ziglang, auditwheel" 2>/dev/null ||
  ! [ -x "$VENV/bin/maturin" ]; then
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install --quiet -r python/wheel-requirements.txt
fi
export PATH="$PWD/$VENV/bin:$PATH"

mkdir -p dist
for arch in "${ARCHES[@]}"; do
  case $arch in x86_64 | aarch64) ;; *) echo "unknown architecture: $arch" >&2; exit 2 ;; esac
  rustup target add "$arch-unknown-linux-gnu" >/dev/null
  rm -f dist/kiss_odom-*"$arch".whl
  SECONDS=0
  maturin build --release --zig --target "$arch-unknown-linux-gnu" \
    --compatibility manylinux2014 --manifest-path python/Cargo.toml --out dist
  wheel=$(ls dist/kiss_odom-*"$arch".whl)
  echo "built $wheel in $SECONDS s"
  # auditwheel names the tags the wheel is consistent with and every library it links.
  report=$(auditwheel show "$wheel")
  echo "$report"
  if ! grep -q "${MANYLINUX}_$arch" <<<"$report"; then
    echo "FAILED: $wheel is not ${MANYLINUX}_$arch" >&2
    exit 1
  fi
  # Anything auditwheel would have to graft into the wheel is a library users may not have.
  if grep -qi "requires external shared libraries\|would graft" <<<"$report"; then
    echo "FAILED: $wheel needs shared libraries outside the manylinux set" >&2
    exit 1
  fi
done

rm -f dist/kiss_odom-*.tar.gz
maturin sdist --manifest-path python/Cargo.toml --out dist
ls -l dist/
