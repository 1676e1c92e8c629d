#!/usr/bin/env python3
"""Prints BENCHMARKS.md section 12's table "Robust mode against the reference and GenZ-ICP"
from bench/degeneracy.sh's results.

    python3 bench/degeneracy_table.py RESULTS.jsonl
"""

import json
import sys
from collections import defaultdict


def fmt(x, f):
    return "n/a" if x is None else f.format(x)


def main():
    runs = defaultdict(dict)
    for line in open(sys.argv[1]):
        r = json.loads(line)
        runs[r["run"]][r["system"].split("-")[0]] = r
    print("| run | frames | reference: KITTI % / ATE m | robust: KITTI % / ATE m | plane frames "
          "| GenZ-ICP: KITTI % / ATE m (preset) | distance est./true: reference / robust / GenZ "
          "| robust/reference f/s | robust <= GenZ | robust within reference + 0.02 pp / + 5 % |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, s in runs.items():
        ref, rob, gz = s.get("reference"), s.get("robust"), s.get("genz")
        cell = lambda r: f"{fmt(r.get('kitti_t_err_pct'), '{:.3f}')} / {fmt(r['ate_m'], '{:.3f}')}"
        ok = "n/a"
        if rob and gz:
            pairs = [(rob.get(k), gz.get(k)) for k in ("kitti_t_err_pct", "ate_m")]
            ok = "yes" if all(a is None or b is None or a <= b for a, b in pairs) else "no"
        bound = "n/a"
        if rob and ref:
            k = (rob.get("kitti_t_err_pct"), ref.get("kitti_t_err_pct"))
            within = (k[0] is None or k[1] is None or k[0] <= k[1] + 0.02) \
                and rob["ate_m"] <= 1.05 * ref["ate_m"]
            bound = "yes" if within else "no"
        path = " / ".join(fmt(r.get("path_ratio"), "{:.2f}") for r in (ref, rob, gz))
        print(f"| {name} | {ref['frames']} | {cell(ref)} | {cell(rob)} | {rob.get('plane_frames', 'n/a')} "
              f"| {cell(gz)} ({gz['system'][5:]}) | {path} | {rob['hz'] / ref['hz']:.2f} | {ok} "
              f"| {bound} |")


if __name__ == "__main__":
    main()
