# Sourced by compare.sh and probes.sh (with `here` set to embedded/): when QEMU could not be
# installed (install-qemu.sh's marker) or a system emulator is missing, prints "SKIP: ..." and
# exits the calling script with 0, as the QEMU stages are specified to do.
if [ -f "$here/target/qemu-skipped" ]; then
  echo "SKIP: $(cat "$here/target/qemu-skipped") (marker from install-qemu.sh)"
  exit 0
fi
for q in qemu-system-arm qemu-system-aarch64 qemu-system-riscv32; do
  if ! command -v "$q" >/dev/null; then
    echo "SKIP: $q not installed (run embedded/install-qemu.sh)"
    exit 0
  fi
done
