#!/usr/bin/env python3
"""Prints BENCHMARKS.md section 15's table "Against kiss-icp, GenZ-ICP and MAD-ICP" from
bench/accurate.sh's results.

    python3 bench/accurate_table.py RESULTS.jsonl

A run is won when the preset's KITTI relative error (where the run is long enough to have
one) and ATE are at or below both kiss-icp's (our default mode) and GenZ-ICP's.
"""

import json
import sys
from collections import defaultdict


def cell(r):
    if r is None:
        return "n/a"
    k = r.get("kitti_t_err_pct")
    return f"{'-' if k is None else f'{k:.3f}'} / {r['ate_m']:.3f}"


def at_or_below(a, b):
    pairs = [(a.get(k), b.get(k)) for k in ("kitti_t_err_pct", "ate_m")]
    return all(x is None or y is None or x <= y for x, y in pairs)


def main():
    runs = defaultdict(dict)
    for line in open(sys.argv[1]):
        r = json.loads(line)
        runs[r["run"]][r["system"].split("-")[0]] = r
    print("| run | kiss-icp (default): KITTI % / ATE m | accurate | GenZ-ICP (preset) "
          "| MAD-ICP | accurate in f32 (ATE f32/f64) | accurate wins |")
    print("|---|---|---|---|---|---|---|")
    won = measured = 0
    for name, s in runs.items():
        ref, acc, gz, mad, f32 = (
            s.get(k) for k in ("default", "accurate", "genz", "mad", "accuratef32"))
        wins = acc is not None and all(at_or_below(acc, o) for o in (ref, gz) if o)
        won += wins
        measured += acc is not None
        preset = f" ({gz['system'][5:]})" if gz else ""
        f32_ratio = f" ({f32['ate_m'] / acc['ate_m']:.2f})" if f32 and acc else ""
        print(f"| {name} | {cell(ref)} | **{cell(acc)}** | {cell(gz)}{preset} | {cell(mad)} "
              f"| {cell(f32)}{f32_ratio} "
              f"| {'not run' if acc is None else 'yes' if wins else 'no'} |")
    print(f"\naccurate at or below kiss-icp and GenZ-ICP on {won} of the {measured} runs it ran")


if __name__ == "__main__":
    main()
