#!/usr/bin/env bash
# Builds the bare-metal program for one target and runs it under QEMU; exits with the
# program's status (124 if QEMU timed out, 96 if the build failed, 97 if an allocator linked).
#
#   embedded/run.sh <thumbv7em|m7|aarch64|riscv32|host> [cargo build args...]
#
# The target picks the default profile (KISS_FEATURES overrides it; extra args are added):
#   thumbv7em  Cortex-M4F, mps2-an386    f32, Quantized, Capacities::SMALL       (features: none)
#   m7         Cortex-M7 (double-precision FPU), mps2-an500, same profile; small profiles only
#   aarch64    Cortex-A53, virt          f64, Exact,     Capacities::FULL_SCALE  (f64,exact,full)
#   riscv32    RV32IMAC,   virt          f32, Quantized, Capacities::SMALL       (none; add --features f64)
#   host       the host twin (same lines, no QEMU), for compare.sh
# Examples:
#   embedded/run.sh riscv32 --features f64
#   KISS_FEATURES= embedded/run.sh aarch64          # the Cortex-M profile on the A53
#   embedded/run.sh thumbv7em --features defmt      # defmt frames; decoded if defmt-print exists
#
# Before the program's output it prints `size` (llvm-size) and `alloc_symbols` (llvm-nm) lines
# for the ELF; on Cortex-M it runs QEMU with plugin/insncount.c and appends `cost` lines per
# frame and the program's total. Environment: KISS_QEMU_TIMEOUT (seconds), KISS_FEATURES,
# KISS_TARGET_DIR (default: embedded/target/<target>), CARGO_TARGET_DIR
# (host twin only; default embedded/target/host), DEFMT_LOG (default info).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here"

usage() { sed -n '2,22p' "$0" >&2; exit 64; }
[ $# -ge 1 ] || usage
which="$1"
shift

case "$which" in
  thumbv7em)
    triple=thumbv7em-none-eabihf
    default_features=""
    timeout_s=120
    # shellcheck disable=SC2054 # the commas belong to one -semihosting-config argument
    qemu=(qemu-system-arm -machine mps2-an386 -nographic -monitor none -serial none
          -semihosting-config enable=on,target=native)
    ;;
  m7)
    # Cortex-M7 with double-precision FPU (FPv5-D16): same target, cortex-m7 codegen, on the
    # AN500 board, which has the same code memory and SRAM but no PSRAM (small profiles only).
    triple=thumbv7em-none-eabihf
    default_features=""
    timeout_s=120
    export RUSTFLAGS="-C target-cpu=cortex-m7"
    # shellcheck disable=SC2054
    qemu=(qemu-system-arm -machine mps2-an500 -nographic -monitor none -serial none
          -semihosting-config enable=on,target=native)
    ;;
  aarch64)
    triple=aarch64-unknown-none
    default_features="f64,exact,full"
    timeout_s=120
    qemu=(qemu-system-aarch64 -machine virt -cpu cortex-a53 -m 256M -nographic -monitor none
          -serial none -nic none -semihosting -icount shift=0)
    ;;
  riscv32)
    triple=riscv32imac-unknown-none-elf
    default_features=""
    timeout_s=600
    qemu=(qemu-system-riscv32 -machine virt -bios none -m 256M -nographic -monitor none
          -serial none -semihosting -icount shift=0)
    ;;
  host)
    triple="$(rustc -vV | awk '/^host:/{print $2}')"
    default_features=""
    timeout_s=0
    ;;
  *) usage ;;
esac
features="${KISS_FEATURES-$default_features}"
timeout_s="${KISS_QEMU_TIMEOUT:-$timeout_s}"

# One target dir per run.sh target: cargo keeps each feature set's artifacts side by side in
# it, so switching profiles re-links nothing, and the dependencies are built once per target.
if [ -n "${KISS_TARGET_DIR:-}" ]; then
  tdir="$KISS_TARGET_DIR"
elif [ "$which" = host ]; then
  tdir="${CARGO_TARGET_DIR:-$here/target/host}"
else
  tdir="$here/target/$which"
fi
# The tiny profile embeds sweeps of a generated VLP-16 drive (kiss-odom simulate, deterministic):
# make them once, with the host tool of this repository (built for the host: without the
# bare-metal code-generation flags this script may have exported above), or the one
# KISS_ODOM_BIN names.
kiss_odom() {
  if [ -n "${KISS_ODOM_BIN:-}" ]; then
    "$KISS_ODOM_BIN" "$@"
  else
    (cd "$here/.." && env -u RUSTFLAGS -u CARGO_ENCODED_RUSTFLAGS -u CARGO_BUILD_TARGET \
      cargo run --release -q -p kiss-odom -- "$@")
  fi
}
# `imu`: a hand-held walk with the IMU's samples at 200 Hz instead.
if [[ ",$features," == *",tiny,"* ]] || [[ ",$features," == *",imu,"* ]]; then
  if [[ ",$features," == *",imu,"* ]]; then
    vlp="${KISS_EMBED_VLP16:-$here/target/vlp16-imu}"; sim=(--profile handheld --imu-rate 200)
  else
    vlp="${KISS_EMBED_VLP16:-$here/target/vlp16}"; sim=()
  fi
  if [ ! -f "$vlp/sim.toml" ]; then
    kiss_odom simulate --out "$vlp" --frames 40 "${sim[@]}" \
      --seed 11 --beams 16 --columns 1800 --fov-up 15 --fov-down -15 --max-range 100 \
      --overwrite >&2 || { echo "error: cannot generate the VLP-16 sweeps" >&2; exit 96; }
  fi
  export KISS_EMBED_VLP16="$vlp"
  # `localize`: the same drive revisited (the other way, the scene changed), localized in a
  # map of the first drive built from its ground truth at Config::tiny's 50 m and 2 m voxels.
  if [[ ",$features," == *",localize,"* ]]; then
    revisit="${vlp}-revisit"
    if [ ! -f "$revisit/sim.toml" ]; then
      kiss_odom simulate --out "$revisit" --frames 40 "${sim[@]}" --revisit \
        --seed 11 --beams 16 --columns 1800 --fov-up 15 --fov-down -15 --max-range 100 \
        --overwrite >&2 || { echo "error: cannot generate the revisit" >&2; exit 96; }
    fi
    map="${KISS_EMBED_MAP:-$vlp/map-tiny.komap}"
    if [ ! -f "$map" ]; then
      kiss_odom map build "$vlp" --poses "$vlp/poses.txt" --max-range 50 \
        --set mapping.voxel_size=2 --points-per-voxel 3 --out "$map" >&2 \
        || { echo "error: cannot build the prior map" >&2; exit 96; }
    fi
    export KISS_EMBED_VLP16="$revisit" KISS_EMBED_MAP="$map"
  fi
fi
# The packets profile embeds the UDP payloads of a generated VLP-16 recording (the same drive).
# `far`: a suburban drive, 36 sweeps from the fifth, over which TINY's map fills at 100 m.
# `mid360`: the same drive seen by a Livox Mid-360; `hesai`: by a Hesai (KISS_EMBED_HESAI);
# `velodyne`, `robosense`: by the Velodyne or Robosense model KISS_EMBED_MODEL names.
if [[ ",$features," == *",packets,"* ]]; then
  sensor=vlp16
  if [[ ",$features," == *",far,"* ]]; then
    pcapdir="${KISS_EMBED_PCAP:-$here/target/vlp16-suburban-pcap}"; sim=(--frames 40 --profile suburban)
    export KISS_EMBED_FIRST="${KISS_EMBED_FIRST:-4}" KISS_EMBED_FRAMES="${KISS_EMBED_FRAMES:-36}"
  elif [[ ",$features," == *",mid360,"* ]]; then
    sensor=mid360; pcapdir="${KISS_EMBED_PCAP:-$here/target/mid360-pcap}"; sim=(--frames 36)
  elif [[ ",$features," == *",hesai,"* ]]; then
    # `hesai`: the model KISS_EMBED_HESAI names (default xt32), sweeps 2-4 of a 6-sweep drive
    # (the AT128's 600-packet frames: 2-3, to fit the board's code memory).
    sensor="${KISS_EMBED_HESAI:-xt32}"; pcapdir="${KISS_EMBED_PCAP:-$here/target/$sensor-pcap}"
    sim=(--frames 6)
    frames=3; [ "$sensor" = at128 ] && frames=2
    export KISS_EMBED_HESAI="$sensor" KISS_EMBED_FIRST="${KISS_EMBED_FIRST:-2}" \
      KISS_EMBED_FRAMES="${KISS_EMBED_FRAMES:-$frames}"
  elif [[ ",$features," == *",velodyne,"* ]] || [[ ",$features," == *",robosense,"* ]]; then
    # `velodyne`, `robosense`: the model KISS_EMBED_MODEL names (vlp32ab, hdl64e-s2, hdl64e-s3,
    # vls128; rs16, rs32, bpearl, helios, helios16p, ruby, airy, m1, e1r),
    # sweeps 2-4 of a 6-sweep drive.
    sensor="${KISS_EMBED_MODEL:?KISS_EMBED_MODEL: the model (hdl64e-s3, vls128, helios...)}"
    pcapdir="${KISS_EMBED_PCAP:-$here/target/$sensor-pcap}"; sim=(--frames 6)
    export KISS_EMBED_MODEL="$sensor" KISS_EMBED_FIRST="${KISS_EMBED_FIRST:-2}" \
      KISS_EMBED_FRAMES="${KISS_EMBED_FRAMES:-3}"
  else
    pcapdir="${KISS_EMBED_PCAP:-$here/target/vlp16-pcap}"; sim=(--frames 36)
  fi
  if [ ! -f "$pcapdir/sim.toml" ]; then
    kiss_odom simulate --out "$pcapdir" "${sim[@]}" \
      --seed 11 --sensor "$sensor" --format pcap --max-range 100 --overwrite >&2 \
      || { echo "error: cannot generate the $sensor pcap" >&2; exit 96; }
  fi
  export KISS_EMBED_PCAP="$pcapdir"
fi
args=(--release --target "$triple" --target-dir "$tdir")
[ -n "$features" ] && args+=(--features "$features")
export DEFMT_LOG="${DEFMT_LOG:-info}"
# A failed build must not pass for the program's own status (cargo exits 101, like a panic).
cargo build --quiet "${args[@]}" "$@" >&2 || { echo "error: build failed" >&2; exit 96; }
elf="$tdir/$triple/release/kiss-odom-embedded"

if [ "$which" = host ]; then
  exec "$elf"
fi

tools="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | awk '/^host:/{print $2}')/bin"
if [ -x "$tools/llvm-size" ]; then
  "$tools/llvm-size" -A "$elf" | awk '
    $1==".text"{t=$2} $1==".rodata"{r=$2} $1==".data"{d=$2} $1==".bss"{b=$2}
    $1==".psram"{p=$2} $1==".stack"{s=$2}
    END{printf "size text=%d rodata=%d data=%d bss=%d psram=%d stack_region=%d\n", t, r, d, b, p, s}'
  # No heap: a global allocator would bring these symbols in.
  n=$("$tools/llvm-nm" "$elf" | grep -cE '__rust_alloc|__rdl_alloc|__rg_alloc|__rust_no_alloc_shim|GlobalAlloc' || true)
  echo "alloc_symbols $n"
  if [ "$n" != 0 ]; then
    echo "error: allocator symbols linked into $elf" >&2
    exit 97
  fi
else
  echo "size unavailable: rustup component add llvm-tools" >&2
fi

plugin_args=()
log=""
if [ "$which" = thumbv7em ] || [ "$which" = m7 ]; then
  so="$here/target/plugin/libinsncount.so"
  if [ ! -f "$so" ] || [ "$here/plugin/insncount.c" -nt "$so" ]; then
    mkdir -p "$(dirname "$so")"
    gcc -shared -fPIC -O2 -o "$so" "$here/plugin/insncount.c" || so=""
  fi
  if [ -n "$so" ] && [ -x "$tools/llvm-nm" ]; then
    mark=$("$tools/llvm-nm" "$elf" | awk '$3=="kiss_frame_mark"{print $1}')
    log="$(mktemp)"
    plugin_args=(-plugin "$so,mark=0x${mark:-0}" -d plugin -D "$log")
  fi
fi

status=0
if [[ ",$features," == *",defmt,"* ]] || [[ " $* " == *defmt* ]]; then
  raw="$tdir/$triple/release/output.defmt"
  timeout "$timeout_s" "${qemu[@]}" "${plugin_args[@]}" -kernel "$elf" > "$raw" || status=$?
  if command -v defmt-print >/dev/null; then
    defmt-print -e "$elf" < "$raw" || true
  else
    echo "defmt frames in $raw ($(wc -c < "$raw") bytes); decode with: defmt-print -e $elf < $raw"
  fi
else
  timeout "$timeout_s" "${qemu[@]}" "${plugin_args[@]}" -kernel "$elf" || status=$?
fi
[ "$status" = 124 ] && echo "error: QEMU timed out after ${timeout_s}s" >&2

if [ -n "$log" ]; then
  # Marks come in pairs around each frame's register_frame call (with `localize`, a second
  # pair around its localization: `cost_localize`).
  loc=0; [[ ",$features," == *",localize,"* ]] && loc=1
  awk -v loc="$loc" '/^mark:/{m[n++]=$2} /^insns:/{t=$2}
       END{for(i=0;i+1<n;i+=2) { k=i/2; c=m[i+1]-m[i]
             if (loc && k%2) { printf "cost_localize %d insns=%.0f counter=qemu-plugin\n", (k-1)/2, c; l+=c }
             else { printf "cost %d insns=%.0f counter=qemu-plugin\n", loc ? k/2 : k, c; s+=c } }
           if (n >= 2) printf "insns frames_total=%.0f counter=qemu-plugin\n", s
           if (loc && n >= 4) printf "insns localize_total=%.0f counter=qemu-plugin\n", l
           if (t != "") printf "insns program_total=%.0f counter=qemu-plugin\n", t}' "$log"
  rm -f "$log"
fi
exit "$status"
