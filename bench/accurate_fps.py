"""Reproduces BENCHMARKS.md section 15, "Speed against kiss-icp": frames per second of the
`accurate` preset and of the default mode against kiss-icp 1.3.0, one thread each, same frames,
in the same run. bench/accurate_fps.sh makes the data and the venv and runs it; by hand:

    DEV=target/release/kiss-odom-dev target/pyvenv/bin/python bench/accurate_fps.py [--repeats N] DATA...

DATA is a KITTI `sequences/NN` folder or a `kiss-odom simulate` folder (its per-point times
deskew, as they do for kiss-odom). kiss-icp runs in this process on frames read beforehand
(`max_num_threads` 1; the time of its `register_frame` calls); kiss-odom runs as `kiss-odom
bench --no-reference --threads 1` (frames preloaded, the time of the core's calls), once with
each preset. The three alternate, repeat by repeat, and the best of each is kept. Timing only:
the presets' poses are not kiss-icp's (the default's are, bit for bit, which CI checks).
Prints a Markdown table of frames/s and the ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import tempfile
import time
from pathlib import Path

import kiss_odom
import numpy as np
from kiss_icp.config import load_config
from kiss_icp.kiss_icp import KissICP

REPO = Path(__file__).resolve().parents[1]
DEV = os.environ.get("DEV", str(REPO / "target/release/kiss-odom-dev"))


def frames(data: Path):
    """The frames as kiss-odom reads them: KITTI scans with kiss-icp's elevation correction."""
    kitti = (data / "calib.txt").exists()
    for f in sorted((data / "velodyne").glob("*.bin")):
        pts = np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        stamps = data / "timestamps" / f.name
        if kitti:
            yield kiss_odom.correct_kitti_scan(pts), np.array([])
        else:
            yield pts, (np.fromfile(stamps, dtype="<f8") if stamps.exists() else np.array([]))


def kiss_icp_seconds(loaded) -> float:
    config = load_config(None)
    config.registration.max_num_threads = 1
    odom = KissICP(config)
    spent = 0.0
    for pts, stamps in loaded:
        t0 = time.perf_counter()
        odom.register_frame(pts, stamps)
        spent += time.perf_counter() - t0
    return spent


def kiss_odom_seconds(data: Path, preset: str) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.json"
        subprocess.run([DEV, "bench", str(data), "--no-reference", "--threads", "1",
                        "--repeats", "1", "--preset", preset, "--json", str(out)],
                       check=True, capture_output=True)
        j = json.loads(out.read_text())
    return j["frames"] / j["ours"]["fps"]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("data", nargs="+", type=Path)
    a = p.parse_args()
    print(f"# {platform.processor() or platform.machine()}, {a.repeats} repeats, best of each, "
          "1 thread")
    print("| data | frames | kiss-icp f/s | default f/s | accurate f/s | default / kiss-icp "
          "| accurate / kiss-icp | accurate / default |")
    print("|---|---|---|---|---|---|---|---|")
    for data in a.data:
        loaded = list(frames(data))
        best = {"kiss-icp": float("inf"), "default": float("inf"), "accurate": float("inf")}
        for _ in range(a.repeats):
            best["kiss-icp"] = min(best["kiss-icp"], kiss_icp_seconds(loaded))
            for preset in ("default", "accurate"):
                best[preset] = min(best[preset], kiss_odom_seconds(data, preset))
        n = len(loaded)
        hz = {k: n / v for k, v in best.items()}
        print(f"| {data.name if not (data / 'calib.txt').exists() else 'kitti-' + data.name} "
              f"| {n} | {hz['kiss-icp']:.1f} | {hz['default']:.1f} | {hz['accurate']:.1f} "
              f"| {hz['default'] / hz['kiss-icp']:.2f} | {hz['accurate'] / hz['kiss-icp']:.2f} "
              f"| {hz['accurate'] / hz['default']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
