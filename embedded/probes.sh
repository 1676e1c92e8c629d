#!/usr/bin/env bash
# Negative controls for the bare-metal program, per target:
#   alloc-probe  code that needs a heap must FAIL TO LINK (no global allocator exists);
#   panic-probe  a panic must exit 101 (semihosting panic handler);
#   fault-probe  an undefined instruction must exit 99 (HardFault / exception vector / trap).
#
#   embedded/probes.sh [thumbv7em aarch64 riscv32]
#
# The probes build in the same target dirs as run.sh (only this crate is rebuilt per probe).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck source=qemu-or-skip.sh
source "$here/qemu-or-skip.sh"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(thumbv7em aarch64 riscv32)
failed=0
check() { # name expected actual
  if [ "$2" = "$3" ]; then echo "PASS $1: $3"; else echo "FAIL $1: expected $2, got $3"; failed=1; fi
}
for t in "${targets[@]}"; do
  case "$t" in
    thumbv7em) triple=thumbv7em-none-eabihf ;;
    aarch64) triple=aarch64-unknown-none ;;
    riscv32) triple=riscv32imac-unknown-none-elf ;;
    *) echo "unknown target $t" >&2; exit 64 ;;
  esac
  log="$(mktemp)"
  if (cd "$here" && cargo build --quiet --release --target "$triple" --target-dir "$here/target/$t" \
        --features alloc-probe) > "$log" 2>&1; then
    check "$t alloc-probe" "link error" "linked"
  elif grep -q "no global memory allocator found" "$log"; then
    check "$t alloc-probe" "link error" "link error"
  else
    check "$t alloc-probe" "link error" "other build error: $(grep -m1 error "$log")"
  fi
  rm -f "$log"
  for p in panic:101 fault:99; do
    s=0
    KISS_FEATURES="${p%%:*}-probe" "$here/run.sh" "$t" > /dev/null 2>&1 || s=$?
    check "$t ${p%%:*}-probe" "exit ${p##*:}" "exit $s"
  done
done
[ "$failed" = 0 ] && echo "probes: all negative controls behaved" || echo "probes: FAILED"
exit "$failed"
