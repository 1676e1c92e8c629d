#!/usr/bin/env bash
# Builds tests/copper (cu-hesai and cu-livox 1.3.0 from the crate registry, with the copper
# runtime they need: about 5 minutes on two cores) and runs the Hesai and Livox decoder tests
# with it, which then compare every point of the shared recordings with the copper-rs parsers'.
# Not in .ci/run: the copper runtime's build would cost the CI more than the comparison.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --quiet --manifest-path tests/copper/Cargo.toml
export KISS_ODOM_COPPER_DUMP="$PWD/tests/copper/target/release/copper-dump"
cargo test --release -p kiss-odom-tests --test workspace -- --nocapture sensors_hesai:: sensors_livox:: \
  sensors_simulated::copper
