#!/usr/bin/env bash
# The house's layers, checked: the libraries others reuse (readers, simulator, driver) and the
# Python bindings build without the command line's crates (clap, plotters, indicatif, the
# `kiss-odom` CLI crate), and the core and sensor decoders stay no_std with no allocator crate.
set -euo pipefail
cd "$(dirname "$0")/.."
failed=0
deps() { # deps DIR ARGS...: the normal dependencies' names, one per line
  local dir=$1
  shift
  (cd "$dir" && cargo tree --locked -e normal --prefix none --format '{p}' "$@") |
    awk '{print $1}' | sort -u
}
refuse() { # refuse WHAT NAMES DEPS
  local hit
  hit=$(grep -xE "$2" <<<"$3" || true)
  if [ -n "$hit" ]; then
    echo "FAIL: $1 depends on $(tr '\n' ' ' <<<"$hit")"
    failed=1
  else
    echo "ok: $1 builds without $2"
  fi
}
CLI='clap|plotters|indicatif|kiss-odom'
for crate in kiss-odom-io kiss-odom-sim kiss-odom-drive; do
  refuse "$crate" "$CLI" "$(deps . -p "$crate")"
done
refuse "python/ (kiss-odom-python)" "$CLI" "$(deps python)"
refuse "fuzz/ (kiss-odom-fuzz)" "$CLI|kiss-odom-drive|kiss-odom-sim" "$(deps fuzz)"
for crate in kiss-odom-core kiss-odom-sensors; do
  refuse "$crate" 'std|alloc|anyhow|serde|kiss-odom-io' "$(deps . -p "$crate")"
done
exit "$failed"
