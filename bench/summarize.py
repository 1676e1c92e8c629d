#!/usr/bin/env python3
"""Prints the figures of BENCHMARKS.md section 2 (the all-threads ratios) and section 3 ("High-water
marks and margins", the reference's columns of "The map against the reference's", the small
configuration's accuracy) and section 6 (peak RSS over the sequence length) from what bench/run_all.sh's
`speed`, `rss` and `small` steps wrote.

    python3 bench/summarize.py [OUT]     (default target/bench/run-all/results)
"""

import json
import sys
from pathlib import Path

OUT = Path(sys.argv[1] if len(sys.argv) > 1 else "target/bench/run-all/results")
MIB = 1 << 20


def speed():
    rows = []
    for f in sorted((OUT / "speed").glob("*.json")):
        r = json.loads(f.read_text())
        o, ref = r["ours"], r.get("reference") or {}
        rows.append((f.stem, r, o, ref))
    print("| run | threads | ours f/s | ref f/s | ours/ref (paired runs) | ours p50 / p99 / max ms "
          "| p99/p50 | max/p50 | ref p50 / p99 / max ms | poses vs ref (m) | bit-identical runs |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, r, o, ref in rows:
        runs = " ".join(f"{x:.2f}" for x in r["speed_ratio_runs"])
        print(
            f"| {name} | {r['threads']} | {o['fps']:.1f} | {ref.get('fps', float('nan')):.1f} "
            f"| **{r['speed_ratio']:.2f}x** ({runs}) "
            f"| {o['p50_ms']:.1f} / {o['p99_ms']:.1f} / {o['max_ms']:.1f} "
            f"| {o['p99_ms'] / o['p50_ms']:.2f} | {o['max_ms'] / o['p50_ms']:.2f} "
            f"| {ref.get('p50_ms', 0):.1f} / {ref.get('p99_ms', 0):.1f} / {ref.get('max_ms', 0):.1f} "
            f"| {r['pose_diff_m']:.1e} | {r['ours_repeatable']} |"
        )
    print()
    print("| run | our state MiB (fixed / at high water) | our map MiB (fixed / at high water) "
          "| ref voxels | ref map MiB (480 B/voxel / with table) | ours fixed / ref "
          "| ours peak RSS / growth MiB | ref peak RSS / growth MiB | high water / capacity |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, r, o, ref in rows:
        m = r["memory"]
        hw = ", ".join(f"{k} {v[0]}/{v[1]}" for k, v in m["high_water"].items())
        rb, rbt = m.get("reference_map_bytes") or 0, m.get("reference_map_bytes_with_table") or 0
        print(
            f"| {name} | {m['state_bytes'] / MIB:.2f} / {(m['state_high_water_bytes'] or 0) / MIB:.2f} "
            f"| {m['map_bytes'] / MIB:.2f} / {m['map_high_water_bytes'] / MIB:.2f} "
            f"| {m.get('reference_voxels')} | {rb / MIB:.2f} / {rbt / MIB:.2f} "
            f"| {m['map_bytes'] / max(rb, 1):.2f} / {m['map_bytes'] / max(rbt, 1):.2f} "
            f"| {(o['peak_rss_bytes'] or 0) / MIB:.1f} / {(o['rss_growth_bytes'] or 0) / MIB:.1f} "
            f"| {(ref.get('peak_rss_bytes') or 0) / MIB:.1f} / {(ref.get('rss_growth_bytes') or 0) / MIB:.1f} "
            f"| {hw} |"
        )


def rss():
    d = OUT / "rss"
    if not d.is_dir():
        return
    print()
    print("| frames | peak RSS MiB | state MiB | frames/s |")
    print("|---|---|---|---|")
    for run in sorted(d.glob("run-*"), key=lambda p: int(p.name.split("-")[1])):
        s = json.loads((run / "summary.json").read_text())
        print(f"| {s['frames']} | {s['peak_rss_bytes'] / MIB:.1f} | {s['state_bytes'] / MIB:.2f} "
              f"| {s['hz']:.1f} |")


def small():
    d = OUT / "small"
    if not d.is_dir():
        return
    print()
    print("| sequence | configuration | state MiB | ATE m | final error m | RPE mean m | "
          "frames with capacity drops |")
    print("|---|---|---|---|---|---|---|")
    for run in sorted(d.iterdir()):
        s = json.loads((run / "summary.json").read_text())
        m = s.get("metrics") or {}
        seq, _, conf = run.name.partition("-full")
        if not conf and run.name.endswith("-small"):
            seq, conf = run.name[: -len("-small")], "small (f32, quantized, 50 m)"
        else:
            conf = "full (f64, exact, " + ("50 m)" if conf == "-50m" else "100 m)")
        cap = s["degraded_frames"].get("capacity", 0)
        print(f"| {seq} | {conf} | {s['state_bytes'] / MIB:.2f} | {m.get('ate_m', float('nan')):.4f} "
              f"| {m.get('final_error_m', float('nan')):.4f} | {m.get('rpe_m_mean', float('nan')):.4f} "
              f"| {cap} |")


if __name__ == "__main__":
    if (OUT / "machine.txt").exists():
        print((OUT / "machine.txt").read_text())
    if (OUT / "speed").is_dir():
        speed()
    rss()
    small()
