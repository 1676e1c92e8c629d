"""Frames per second of `kiss_odom.KissICP` against kiss-icp 1.3.0's `KissICP`, same process,
same preloaded frames, one thread each (kiss-icp's `max_num_threads = 1`, ours `threads=1`).

Usage: python python/bench/fps.py [--repeats N] [--generated DIR]...
Prints one row per sequence (best-of-N seconds per frame for each side, and the ratio) and
checks on the way that both sides' poses agree (1e-9 m), so the timed work is the same work.
Timing only: no assertion on speed.
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import numpy as np

import kiss_odom
from kiss_icp.config import load_config
from kiss_icp.kiss_icp import KissICP as Reference

REPO = Path(__file__).resolve().parents[2]


def kitti(seq: Path):
    for f in sorted((seq / "velodyne").glob("*.bin")):
        pts = np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        yield kiss_odom.correct_kitti_scan(pts), np.array([])


def generated(folder: Path):
    """A `kiss-odom simulate` folder, with its per-point timestamps (deskewing on)."""
    for f in sorted((folder / "velodyne").glob("*.bin")):
        pts = np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        yield pts, np.fromfile(folder / "timestamps" / f.name, dtype="<f8")


def timed(odom, frames):
    poses, spent = [], 0.0
    for pts, stamps in frames:
        t0 = time.perf_counter()
        odom.register_frame(pts, stamps)
        spent += time.perf_counter() - t0
        poses.append(np.array(odom.last_pose))
    return spent, np.array(poses)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--kitti", default=str(REPO.parent / "shared/data/kitti-mini/sequences"))
    p.add_argument("--generated", action="append", default=[])
    a = p.parse_args()
    config = load_config(None)
    config.registration.max_num_threads = 1
    sets = {f"kitti-mini {s.name}": list(kitti(s)) for s in sorted(Path(a.kitti).iterdir())}
    sets.update({f"generated {Path(g).name}": list(generated(Path(g))) for g in a.generated})
    print(f"# {platform.processor() or platform.machine()}, {a.repeats} repeats, best of each")
    print("| sequence | frames | kiss-icp ms/frame | kiss-odom ms/frame | ratio (frames/s) | worst pose gap (m) |")
    print("|---|---|---|---|---|---|")
    total = [0.0, 0.0]
    for name, frames in sets.items():
        best_ref = best_ours = float("inf")
        for _ in range(a.repeats):
            t_ref, p_ref = timed(Reference(config), frames)
            t_ours, p_ours = timed(kiss_odom.KissICP(config, threads=1), frames)
            best_ref, best_ours = min(best_ref, t_ref), min(best_ours, t_ours)
        gap = float(np.linalg.norm(p_ref[:, :3, 3] - p_ours[:, :3, 3], axis=1).max())
        assert gap <= 1e-9, f"{name}: poses differ by {gap} m: not the same work"
        n = len(frames)
        total[0] += best_ref
        total[1] += best_ours
        print(f"| {name} | {n} | {1e3 * best_ref / n:.1f} | {1e3 * best_ours / n:.1f} | "
              f"{best_ref / best_ours:.2f}x | {gap:.1e} |")
    print(f"| all | | | | {total[0] / total[1]:.2f}x | |")


if __name__ == "__main__":
    main()
