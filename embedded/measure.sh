#!/usr/bin/env bash
# Runs the measurement cases and prints the table of RESULTS.md (markdown) on stdout.
#
#   embedded/measure.sh [case...]
#
# Cases (target:features): m4-small m4-full m4-full-f64 m4-baseline m7-small m7-small-f64 m7-tiny
# m7-imu m7-packets m7-packets-decode m7-mid360 m7-mid360-decode a53-full a53-small rv-small rv-small-f64
# rv-full (default: all), and m7-hesai-MODEL-decode for MODEL xt32 xt16 xt32m pandar40p pandar64
# qt64 at128 (not in the default list: `embedded/measure.sh $(embedded/measure.sh --hesai)`), and
# m7-velodyne-MODEL-decode (vlp32ab hdl64e-s2 hdl64e-s3 vls128), m7-robosense-MODEL-decode (rs16
# rs32 bpearl helios helios16p ruby airy m1 e1r): `embedded/
# measure.sh $(embedded/measure.sh --spinning)`.
# m7-packets streams a generated VLP-16 recording packet by packet through the decoder and the
# core, m7-mid360 a Livox Mid-360 one; the -decode cases run the decoder alone; all four add a
# per-packet line below the table. Outputs go to embedded/target/measure/.
# Frame times are ESTIMATES: instructions / (IPC x clock) with IPC = 1 on a 600 MHz Cortex-M7
# (from the Cortex-M4F counts for an M7 whose FPU is single precision, from the m7 build for
# one with the double-precision FPU) and a 1.2 GHz Cortex-A53 (from the AArch64 counts); see
# RESULTS.md for why IPC 1 and how far off it may be.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/target/measure"
mkdir -p "$out"
hesai=(xt32 xt16 xt32m pandar40p pandar64 qt64 at128)
if [ "${1:-}" = --hesai ]; then
  for m in "${hesai[@]}"; do printf 'm7-hesai-%s-decode ' "$m"; done
  echo
  exit 0
fi
velodyne=(vlp32ab hdl64e-s2 hdl64e-s3 vls128)
robosense=(rs16 rs32 bpearl helios helios16p ruby airy m1 e1r)
if [ "${1:-}" = --spinning ]; then
  for m in "${velodyne[@]}"; do printf 'm7-velodyne-%s-decode ' "$m"; done
  for m in "${robosense[@]}"; do printf 'm7-robosense-%s-decode ' "$m"; done
  echo
  exit 0
fi
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(m4-small m4-full m4-full-f64 m4-baseline m7-small m7-small-f64 m7-tiny m7-imu m7-packets m7-packets-decode m7-mid360 m7-mid360-decode a53-full a53-small rv-small rv-small-f64 rv-full)

spec() {
  case "$1" in
    m4-small) echo "thumbv7em:" ;;
    m4-full) echo "thumbv7em:full" ;;
    m4-full-f64) echo "thumbv7em:f64,exact,full" ;;
    m4-baseline) echo "thumbv7em:baseline" ;;
    m7-small) echo "m7:" ;;
    m7-small-f64) echo "m7:f64" ;;
    m7-tiny) echo "m7:tiny" ;;
    m7-imu) echo "m7:tiny,imu" ;;
    m7-packets) echo "m7:packets" ;;
    m7-packets-decode) echo "m7:packets,baseline" ;;
    m7-mid360) echo "m7:packets,mid360" ;;
    m7-mid360-decode) echo "m7:packets,mid360,baseline" ;;
    # A generated Hesai recording through the decoder alone (KISS_EMBED_HESAI, below).
    m7-hesai-*-decode) echo "m7:packets,hesai,baseline" ;;
    m7-velodyne-*-decode) echo "m7:packets,velodyne,baseline" ;;
    m7-robosense-*-decode) echo "m7:packets,robosense,baseline" ;;
    a53-full) echo "aarch64:f64,exact,full" ;;
    a53-small) echo "aarch64:" ;;
    rv-small) echo "riscv32:" ;;
    rv-small-f64) echo "riscv32:f64" ;;
    rv-full) echo "riscv32:f64,exact,full" ;;
    *) echo "unknown case $1" >&2; exit 64 ;;
  esac
}

for c in "${cases[@]}"; do
  s="$(spec "$c")"
  t0=$(date +%s)
  model=""
  case "$c" in m7-*-*-decode) model="${c#m7-*-}"; model="${model%-decode}" ;; esac
  KISS_EMBED_MODEL="$model" KISS_EMBED_HESAI="$model" KISS_FEATURES="${s#*:}" "$here/run.sh" "${s%%:*}" > "$out/$c.txt"
  echo "$c: $(( $(date +%s) - t0 )) s" >&2
done

echo "| case | target | scalar, codec, capacities | points/frame | .text | .rodata (frames) | .bss + .psram | state bytes | stack high-water | insns frame 0 | insns/frame 1-4 (mean, max) | est. ms/frame M7 600 MHz | est. ms/frame A53 1.2 GHz |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for c in "${cases[@]}"; do
  case "$c" in m4-baseline | *-decode) continue ;; esac
  s="$(spec "$c")"
  awk -v c="$c" -v t="${s%%:*}" '
    /^size /{ for (i=2;i<=NF;i++) { split($i,kv,"="); sz[kv[1]]=kv[2] } }
    /^config /{ for (i=2;i<=NF;i++) { split($i,kv,"="); cf[kv[1]]=kv[2] } }
    /^frame /{ for (i=3;i<=NF;i++) { split($i,kv,"="); if (kv[1]=="points") { pts+=kv[2]; nf++ } } }
    /^memory /{ for (i=2;i<=NF;i++) { split($i,kv,"="); if (kv[1]=="state_bytes") st=kv[2] } }
    /^stack /{ split($2,kv,"="); sk=kv[2] }
    /^cost /{ split($3,kv,"="); n=$2+0; if (n==0) f0=kv[2]; else { sum+=kv[2]; k++; if (kv[2]>mx) mx=kv[2] } }
    END {
      mean = k ? sum/k : 0
      m7 = (t=="thumbv7em" || t=="m7") ? sprintf("%.0f", mean/600e6*1e3) : "-"
      a53 = (t=="aarch64") ? sprintf("%.0f", mean/1.2e9*1e3) : "-"
      printf "| %s | %s | %s, %s, %s | %d | %d | %d | %d | %d | %d | %.1f M | %.1f M, %.1f M | %s | %s |\n",
        c, t, cf["scalar"], cf["codec"], cf["caps"], nf ? pts/nf : 0, sz["text"], sz["rodata"],
        sz["bss"] + sz["psram"], st, sk, f0/1e6, mean/1e6, mx/1e6, m7, a53
    }' "$out/$c.txt"
done
if [ -f "$out/m4-baseline.txt" ] && [ -f "$out/m4-small.txt" ]; then
  b=$(awk -F'[= ]' '/^insns program_total/{print $3}' "$out/m4-baseline.txt")
  f=$(awk -F'[= ]' '/^insns program_total/{print $3}' "$out/m4-small.txt")
  m=$(awk -F'[= ]' '/^insns frames_total/{print $3}' "$out/m4-small.txt")
  echo
  echo "Cortex-M4F m4-small: program $f - baseline $b = $((f - b)) instructions for all frames;" \
       "the per-frame marks add up to $m (the rest is printing the frame lines)."
fi
for c in m7-packets m7-packets-decode m7-mid360 m7-mid360-decode; do
  [ -f "$out/$c.txt" ] || continue
  echo
  # Sweeps 1-4 (sweep 0 has no map to register against).
  awk -v c="$c" '
    /^input /{ for (i=3;i<=NF;i++) { split($i,kv,"="); if (kv[1]=="packets") p[$2]=kv[2] } }
    /^cost /{ split($3,kv,"="); q[$2]=kv[2] }
    END { for (s in q) if (s>0) { n++; sum+=q[s]; pk+=p[s] }
          printf "%s: %.2f M instructions per sweep (sweeps 1-%d, mean), %d packets per sweep, %.0f k instructions per packet\n",
            c, sum/n/1e6, n, pk/n, sum/pk/1e3 }' "$out/$c.txt"
done
# One table a family: a row per model measured.
for family in hesai velodyne robosense; do
rows=()
declare -n models="$family"
for m in "${models[@]}"; do [ -f "$out/m7-$family-$m-decode.txt" ] && rows+=("$m"); done
if [ ${#rows[@]} -gt 0 ]; then
  echo
  echo "| ${family^} model (generated, decoder alone, M7) | packet bytes | packets/sweep | points/sweep | k insns/packet | insns/point | decoder state bytes |"
  echo "|---|---|---|---|---|---|---|"
  for m in "${rows[@]}"; do
    # Sweeps 1 on (sweep 0 is whatever the embedded packets begin with).
    awk -v m="$m" '
      /^decoder /{ for (i=2;i<=NF;i++) { split($i,kv,"="); if (kv[1]=="state_bytes") st=kv[2]; if (kv[1]=="packet_len") len=kv[2] } }
      /^input /{ for (i=3;i<=NF;i++) { split($i,kv,"="); if (kv[1]=="packets") p[$2]=kv[2]; if (kv[1]=="points") q[$2]=kv[2] } }
      /^cost /{ split($3,kv,"="); c[$2]=kv[2] }
      END { for (s in c) if (s>0) { n++; sum+=c[s]; pk+=p[s]; pt+=q[s] }
            printf "| %s | %s | %.0f | %.0f | %.1f | %.0f | %s |\n", m, len, pk/n, pt/n, sum/pk/1e3, sum/pt, st }
    ' "$out/m7-$family-$m-decode.txt"
  done
fi
done
