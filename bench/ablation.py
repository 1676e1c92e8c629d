#!/usr/bin/env python3
"""Prints BENCHMARKS.md's "Every rule on real data" table (run by
bench/ablation.sh): the accurate preset, then the preset with each of its rules off in turn,
then the default, on every given dataset; ATE and mean RPE against its ground truth or
reference trajectory, and frames/s in the core.

    python3 bench/ablation.py BIN OUT DATASET...

DATASET: a folder `run` reads, `NAME=PATH` to name it, `GROUP/NAME=PATH` to put it in a group
of the summary, `@ARGS` after it (one word, comma-separated) for more `run` flags. Each variant
is `run --preset accurate --config VARIANT.toml` (the rule's settings back at the default's
values), one thread. After the table of every run, the summary BENCHMARKS.md shows: per group,
the geometric mean of ATE and of mean RPE without the rule over the preset's, and (in
brackets) the runs whose ATE grew without it.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

# Each rule of Config::accurate and the settings that turn it off (the default's values).
RULES = {
    "r_max/200 voxels": "[mapping]\nvoxel_size = {half}\n",
    "plane terms every frame": "[registration]\nplane_gate = 0.015\n",
    "cycle stop": "[registration]\ncycle_stop = false\n",
    "second deskew": "[data]\nredeskew = false\n",
    "scan-order clouds": "[mapping]\nreference_order = true\n",
    "thinned cloud": "[mapping]\ndesired_source_points = 0\n",
}


def sh(*cmd):
    return subprocess.run([str(c) for c in cmd], check=True, capture_output=True, text=True)


def spec(arg):
    arg, _, extra = arg.partition("@")
    name, _, path = arg.rpartition("=")
    group, _, name = name.rpartition("/")
    path = Path(path)
    return group, name or path.name, path, [a for a in extra.split(",") if a]


def gm(xs):
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else math.nan


def ratios(rows, acc):
    """ATE and mean RPE of `rows` over the preset's `acc`, where both are measured."""
    return [(a / a0, r / r0) for (a, r, _), (a0, r0, _) in zip(rows, acc)
            if a0 > 0 and r0 > 0 and math.isfinite(a) and math.isfinite(r)]


def run(binary, out, path, extra, preset, config=None):
    flags = ["--preset", preset, "--threads", "1", "-q", *extra]
    if config is not None:
        flags += ["--config", config]
    sh(binary, "run", path, "--out", out, *flags)
    s = json.loads((out / "summary.json").read_text())
    m = s.get("metrics") or {}
    return m.get("ate_m", math.nan), m.get("rpe_m_mean", math.nan), s["hz"]


def main():
    binary, out, datasets = sys.argv[1], Path(sys.argv[2]), sys.argv[3:]
    names = ["accurate"] + [f"without {r}" for r in RULES] + ["default"]
    rows = {n: [] for n in names}
    heads, groups = [], []
    for arg in datasets:
        group, name, path, extra = spec(arg)
        heads.append(name)
        groups.append(group)
        base = out / name
        base.mkdir(parents=True, exist_ok=True)
        rows["accurate"].append(run(binary, base / "accurate", path, extra, "accurate"))
        cfg = (base / "accurate" / "config.toml").read_text()
        voxel = float(next(l.split("=")[1] for l in cfg.splitlines()
                           if l.startswith("voxel_size")))
        for rule, toml in RULES.items():
            variant = base / f"without-{rule.replace(' ', '-').replace('/', '')}"
            variant.mkdir(parents=True, exist_ok=True)
            conf = variant / "variant.toml"
            conf.write_text(toml.format(half=repr(2 * voxel)))
            rows[f"without {rule}"].append(
                run(binary, variant / "out", path, extra, "accurate", conf))
        rows["default"].append(run(binary, base / "default", path, extra, "default"))
        print(f"{name}: done", file=sys.stderr, flush=True)
    print("| variant | " + " | ".join(heads) + " | ATE and mean RPE over the preset's, "
          "geometric mean (> 1: the rule helped) |")
    print("|---|" + "---|" * len(heads) + "---|")
    acc = rows["accurate"]
    for n in names:
        cells = [f"{a:.3f} / {r:.4f} / {hz:.1f}" for a, r, hz in rows[n]]
        rs = ratios(rows[n], acc)
        ate_gm, rpe_gm = gm([a for a, _ in rs]), gm([r for _, r in rs])
        print(f"| {n} | " + " | ".join(cells) + f" | {ate_gm:.3f} / {rpe_gm:.3f} |")
    names_of = {g: [i for i, h in enumerate(groups) if h == g] for g in dict.fromkeys(groups)}
    print()
    print("| rule off | " + " | ".join(f"{g or 'all'} ({len(ix)})" for g, ix in names_of.items())
          + " |")
    print("|---|" + "---|" * len(names_of))
    for n in names[1:]:
        cells = []
        for ix in names_of.values():
            rs = ratios([rows[n][i] for i in ix], [acc[i] for i in ix])
            grew = sum(a > 1 for a, _ in rs)
            cells.append(f"{gm([a for a, _ in rs]):.2f} / {gm([r for _, r in rs]):.2f} ({grew})")
        print(f"| {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
