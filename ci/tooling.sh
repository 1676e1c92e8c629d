#!/usr/bin/env bash
# The tooling: the core's proptest properties (release; also part of the README's test command,
# so .ci/run leaves this stage out), every cargo-fuzz target for a bounded time on its committed
# corpus, and Miri on the core's unit tests. Fails on any finding. A stage is skipped, with the
# reason printed, only when its tool cannot be installed.
#
#   ci/tooling.sh [props] [fuzz] [miri]     (default: all three)
#
# FUZZ_SECONDS  seconds of exploration per fuzz target (default 60; 19 targets, so about 19
#               minutes), after a replay of the committed corpus, which must pass
# FUZZ_STRICT   1: new findings of the exploration fail the run too (default: reported)
#
# Fuzzing uses a fixed seed (-seed=1), so a CI run explores what a local run with the same
# budget explored and a red CI is reproducible. -malloc_limit_mb is above what a 32-bit length
# field can ask for: the mcap crate reserves a string map's declared length up front (a 2.5 GB
# malloc from a 3.5 kB file, found by this fuzzer), which the OS grants lazily and the parse
# then rejects; the 2 GB RSS limit still catches memory really used.
# FUZZ_TARGETS  space-separated subset of targets (default: all of `cargo fuzz list`)
# TOOLING_JOBS  2: Miri runs beside the other stages (its log printed after theirs); default 1
# MIRI_TIMEOUT  seconds before Miri counts as a failure (default 900)
# TOOLING_CLEAN 1: delete each stage's build (fuzz/target, target/miri) once it has run, for a
#               machine short of disk (default: kept, so a second run builds nothing)
set -euo pipefail
cd "$(dirname "$0")/.."

FUZZ_SECONDS=${FUZZ_SECONDS:-60}
MIRI_TIMEOUT=${MIRI_TIMEOUT:-900}
CARGO_FUZZ_VERSION=0.13.2
STAGES=${*:-props fuzz miri}

step() { printf '\n=== [%4d s] %s\n' "$SECONDS" "$*"; }
skip() { printf 'SKIP: %s\n' "$*"; }
FAILED=()
FINDINGS=()
SECONDS=0

have_nightly() {
  rustup run nightly rustc --version >/dev/null 2>&1 ||
    rustup toolchain install nightly --profile minimal >/dev/null 2>&1
}

props() {
  step "tooling: proptest properties of the core (release)"
  # Also part of `cargo test --workspace --release`; run on its own here to report it.
  if ! cargo test --workspace --release --test core properties:: -- --nocapture; then
    FAILED+=("proptest properties")
  fi
}

fuzz() {
  step "tooling: cargo-fuzz, ${FUZZ_SECONDS} s per target"
  if ! have_nightly; then
    skip "no nightly toolchain (rustup toolchain install nightly failed); fuzzing skipped"
    return
  fi
  # Unoptimised: it only drives cargo and rustc, and an unoptimised build is quicker.
  if ! cargo fuzz --version >/dev/null 2>&1 &&
    ! cargo install cargo-fuzz --version "$CARGO_FUZZ_VERSION" --locked --debug; then
    skip "cargo install cargo-fuzz failed; fuzzing skipped"
    return
  fi
  # One build for every target, so build time does not eat into the fuzzing budget.
  if ! cargo +nightly fuzz build; then
    FAILED+=("fuzz build")
    return
  fi
  local targets=${FUZZ_TARGETS:-$(cargo +nightly fuzz list)}
  local scratch
  scratch=$(mktemp -d)
  local opts=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=8192)
  for t in $targets; do
    echo "--- fuzz $t: replay of the committed corpus (regression inputs included)"
    if ! cargo +nightly fuzz run "$t" "fuzz/corpus/$t" -- -runs=0 "${opts[@]}" 2>&1 |
      grep -v -E '^#[0-9]+\s+(NEW|REDUCE|pulse)'; then
      FAILED+=("fuzz $t: a committed corpus input fails (see fuzz/artifacts/$t/)")
      continue
    fi
    echo "--- fuzz $t: ${FUZZ_SECONDS} s of exploration"
    # New inputs go to the scratch corpus (first directory); the committed one is only read.
    mkdir -p "$scratch/$t"
    if ! cargo +nightly fuzz run "$t" "$scratch/$t" "fuzz/corpus/$t" -- \
      -seed=1 -max_total_time="$FUZZ_SECONDS" "${opts[@]}" \
      -print_final_stats=1 2>&1 | grep -v -E '^#[0-9]+\s+(NEW|REDUCE|pulse)'; then
      FINDINGS+=("fuzz $t (reproducer in fuzz/artifacts/$t/)")
    fi
  done
  rm -rf "$scratch"
  # The targets that read paths write their input to one tmpfs file per process.
  rm -f /dev/shm/kiss-odom-fuzz-* 2>/dev/null || true
  clean fuzz/target
}

clean() { # clean DIR: with TOOLING_CLEAN=1, the stage's build goes once it has run
  if [ "${TOOLING_CLEAN:-0}" = 1 ]; then rm -rf "$1"; fi
}

miri() {
  step "tooling: Miri on kiss-odom-core's tests"
  if ! have_nightly || ! rustup +nightly component add miri rust-src >/dev/null 2>&1; then
    skip "rustup could not install the nightly miri component; Miri skipped"
    return
  fi
  cargo +nightly miri setup
  # The core's unit tests (src/) minus the ICP runs on whole scenes (cfg_attr(miri, ignore));
  # the integration tests would take hours under Miri. `soft-float` keeps libm off inline
  # assembly, which Miri cannot run. Tree Borrows: under Stacked Borrows Miri reports
  # nalgebra 0.33's own Cholesky (a view retag in `axcpy_uninit`), not code of ours.
  if ! MIRIFLAGS="-Zmiri-tree-borrows" timeout "$MIRI_TIMEOUT" \
    cargo +nightly miri test -p kiss-odom-core --lib --features soft-float; then
    FAILED+=("miri")
  fi
  clean target/miri
}

run_stages() {
  for s in "$@"; do
    case "$s" in
      props | fuzz | miri) "$s" ;;
      *) echo "unknown stage $s (props, fuzz, miri)" >&2; exit 2 ;;
    esac
  done
}

if [ "${TOOLING_JOBS:-1}" = 2 ] && [[ " $STAGES " == *" miri "* ]]; then
  # Miri runs on one core from start to end, and fuzzing after its build runs on one core too:
  # side by side they finish together. Nightly is installed once, before both use it.
  have_nightly || true
  miri_log=$(mktemp)
  (
    miri
    [ ${#FAILED[@]} -eq 0 ]
  ) >"$miri_log" 2>&1 &
  miri_job=$!
  run_stages ${STAGES//miri/}
  miri_status=0
  wait "$miri_job" || miri_status=$?
  cat "$miri_log"
  rm -f "$miri_log"
  if [ "$miri_status" != 0 ]; then FAILED+=("miri"); fi
else
  run_stages $STAGES
fi

step "tooling done in ${SECONDS} s"
if [ ${#FINDINGS[@]} -gt 0 ]; then
  # Exploration is random (and the nightly compiler changes under it), so what it finds new
  # is reported loudly but fails the run only with FUZZ_STRICT=1; a reproducer belongs in
  # fuzz/corpus/<target>/ once fixed, where the replay above makes it fatal for good.
  printf 'FUZZ FINDING: %s\n' "${FINDINGS[@]}"
  if [ "${FUZZ_STRICT:-0}" = 1 ]; then FAILED+=("${FINDINGS[@]}"); fi
fi
if [ ${#FAILED[@]} -gt 0 ]; then
  printf 'FAILED: %s\n' "${FAILED[@]}"
  exit 1
fi
