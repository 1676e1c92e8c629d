#!/usr/bin/env bash
# Runs the bare-metal program under QEMU and its host twin (same source, same features, same
# embedded frames) and checks that every `input`, `frame` and `pose` line agrees character for
# character. Poses are printed with `{:e}`, the shortest decimal that reads back to the same
# bits, so equal text is bit-identical; on a mismatch the largest pose difference is printed.
#
#   embedded/compare.sh [case...]     cases: thumbv7em thumbv7em-full thumbv7em-robust m7 m7-f64
#                                            m7-tiny m7-imu m7-accurate m7-localize m7-packets
#                                            m7-far m7-mid360
#                                            aarch64 aarch64-small
#                                            riscv32 riscv32-f64 riscv32-full
#                                     (default: thumbv7em thumbv7em-robust m7-f64 m7-tiny m7-imu
#                                     m7-accurate m7-localize m7-packets m7-far m7-mid360 aarch64
#                                     riscv32 riscv32-f64)
#
# Outputs go to embedded/target/compare/<case>.{qemu,host}.txt. Exits 0 when all agree, 1 on
# a mismatch or a failed run; prints "SKIP: ..." and exits 0 when QEMU could not be installed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/target/compare"
mkdir -p "$out"

# shellcheck source=qemu-or-skip.sh
source "$here/qemu-or-skip.sh"

cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(thumbv7em thumbv7em-robust m7-f64 m7-tiny m7-imu m7-accurate m7-localize m7-packets m7-far m7-mid360 aarch64 riscv32 riscv32-f64)

failed=0
for c in "${cases[@]}"; do
  case "$c" in
    thumbv7em) target=thumbv7em; features="" ;;
    thumbv7em-full) target=thumbv7em; features="full" ;;
    thumbv7em-robust) target=thumbv7em; features="robust" ;;
    m7) target=m7; features="" ;;
    m7-f64) target=m7; features="f64" ;;
    m7-tiny) target=m7; features="tiny" ;;
    m7-imu) target=m7; features="tiny,imu" ;;
    m7-accurate) target=m7; features="tiny,accurate" ;;
    m7-localize) target=m7; features="tiny,localize" ;;
    m7-packets) target=m7; features="packets" ;;
    m7-far) target=m7; features="packets,far" ;;
    m7-mid360) target=m7; features="packets,mid360" ;;
    aarch64) target=aarch64; features="f64,exact,full" ;;
    aarch64-small) target=aarch64; features="" ;;
    riscv32) target=riscv32; features="" ;;
    riscv32-f64) target=riscv32; features="f64" ;;
    riscv32-full) target=riscv32; features="f64,exact,full" ;;
    *) echo "unknown case $c" >&2; exit 64 ;;
  esac
  echo "=== $c (features: ${features:-none})"
  start=$(date +%s)
  status=0
  KISS_FEATURES="$features" "$here/run.sh" "$target" > "$out/$c.qemu.txt" || status=$?
  mid=$(date +%s)
  if [ "$status" != 0 ]; then
    echo "FAIL $c: $target run exited $status"; tail -n 5 "$out/$c.qemu.txt"
    failed=1
    continue
  fi
  # The host twin embeds the frames the target did (build.rs thins them on the M4F).
  cfg="$(grep -m1 '^config ' "$out/$c.qemu.txt" || true)"
  val() { tr ' ' '\n' <<< "$cfg" | sed -n "s/^$1=//p"; }
  hstatus=0
  KISS_EMBED_SEQUENCE="$(val sequence)" KISS_EMBED_FIRST="$(val first)" \
    KISS_EMBED_FRAMES="$(val frames)" KISS_EMBED_KEEP_EVERY="$(val keep_every)" \
    KISS_FEATURES="$features" "$here/run.sh" host > "$out/$c.host.txt" || hstatus=$?
  if [ "$hstatus" != 0 ]; then
    echo "FAIL $c: host twin exited $hstatus"
    failed=1
    continue
  fi
  pick() { grep -E '^(config|input|frame|pose|imu|localize) ' "$1"; }
  frames=$(grep -c '^pose ' "$out/$c.qemu.txt" || true)
  if [ "$frames" -gt 0 ] && diff <(pick "$out/$c.host.txt") <(pick "$out/$c.qemu.txt") > "$out/$c.diff"; then
    echo "PASS $c: $frames poses bit-identical to the host (qemu run $((mid - start)) s incl. build)"
  else
    echo "FAIL $c: $target and host disagree (see $out/$c.diff)"
    # Largest absolute difference over the pose numbers, frame by frame.
    paste -d' ' <(grep '^pose ' "$out/$c.host.txt") <(grep '^pose ' "$out/$c.qemu.txt") \
      | awk '{ m=0; for (k=3;k<=14;k++) { d=$k-$(k+14); if (d<0) d=-d; if (d>m) m=d }
               printf "  frame %s max |pose difference| %.3e\n", $2, m }'
    failed=1
  fi
  grep -E '^(size|cost|cost_localize|insns|memory|memory_localize|stack) ' "$out/$c.qemu.txt" | sed 's/^/  /'
done
if [ "$failed" = 0 ]; then
  echo "compare: all cases bit-identical"
else
  echo "compare: FAILED"
fi
exit "$failed"
