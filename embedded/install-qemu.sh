#!/usr/bin/env bash
# Installs what the bare-metal runs need: QEMU (arm, aarch64, riscv32), the three Rust targets
# and llvm-tools (llvm-size, llvm-nm). Idempotent. If QEMU cannot be installed it prints
# "SKIP: <reason>", writes the marker embedded/target/qemu-skipped and exits 0, so callers can
# tell "skipped" from "passed".
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
marker="$here/target/qemu-skipped"
mkdir -p "$here/target"
rm -f "$marker"

skip() {
  echo "SKIP: $*"
  echo "$*" > "$marker"
  exit 0
}

rustup target add thumbv7em-none-eabihf aarch64-unknown-none riscv32imac-unknown-none-elf \
  || skip "rustup target add failed"
rustup component add llvm-tools || skip "rustup component add llvm-tools failed"

have_qemu() {
  command -v qemu-system-arm >/dev/null && command -v qemu-system-aarch64 >/dev/null \
    && command -v qemu-system-riscv32 >/dev/null
}
if have_qemu; then
  echo "qemu already installed: $(qemu-system-arm --version | head -n1)"
  exit 0
fi
command -v apt-get >/dev/null || skip "no apt-get: install qemu-system-arm and qemu-system-riscv32 by hand"
sudo=""
if [ "$(id -u)" != 0 ]; then
  command -v sudo >/dev/null || skip "not root and no sudo"
  sudo="sudo -n"
fi
export DEBIAN_FRONTEND=noninteractive

# Debian 12 ships QEMU 7.2, but images that carry qemu-utils from bookworm-backports (10.x) cannot
# install 7.2's qemu-system-common next to it ("Breaks: qemu-system-common (< 1:8.0...)"), so
# on bookworm we take the system emulators from backports too, on the machine's own mirror.
codename="$(. /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}")"
args=()
if [ "$codename" = bookworm ]; then
  src=/etc/apt/sources.list.d/bookworm-backports.sources
  if [ ! -f "$src" ]; then
    uri="$(awk '/^URIs:/{print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null)"
    [ -n "$uri" ] || uri=http://deb.debian.org/debian
    printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
      "$uri" | $sudo tee "$src" >/dev/null || skip "cannot write $src"
  fi
  args=(-t bookworm-backports)
fi
$sudo apt-get update -q || skip "apt-get update failed"
# qemu-system-aarch64 is in qemu-system-arm; qemu-system-riscv32 in qemu-system-riscv, which
# qemu-system-misc pulls in on QEMU 10.
$sudo apt-get install -y -q --no-install-recommends "${args[@]}" qemu-system-arm qemu-system-misc \
  || skip "apt-get install qemu-system-arm qemu-system-misc failed"
have_qemu || skip "QEMU installed but qemu-system-{arm,aarch64,riscv32} not found on PATH"
echo "qemu installed: $(qemu-system-arm --version | head -n1)"
