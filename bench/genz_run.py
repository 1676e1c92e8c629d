"""A peer of BENCHMARKS.md sections 12 and 15 (run by bench/degeneracy.sh, bench/accurate.sh
and bench/spread.sh through bench/peers.sh): GenZ-ICP (PyPI `genz-icp` 0.3.2) on a folder in
kiss-odom's generic layout, its poses written in KITTI format.

    genzvenv/bin/python bench/genz_run.py DATA OUT.txt [--preset NAME] [--no-deskew]

DATA holds `velodyne/NNNNNN.bin` (f32 x, y, z, intensity) and, when deskewing,
`timestamps/NNNNNN.bin` (f64 capture time per point) as `kiss-odom simulate` writes them, or is
a KITTI `sequences/NN` folder (no timestamps). GenZ-ICP's deskew places the scan at timestamp
0.5 of [0, 1]; we give it each sweep's times mapped to [-0.5, 0.5] so that it deskews to the
end of the sweep, where kiss-odom and the simulator's ground truth put the pose. GenZ-ICP keeps
its adaptive voxel size in a C++ `static`, so run one sequence per process.

Prints one JSON line: frames, seconds spent in `register_frame`, the preset used.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from genz_icp.config import load_config
from genz_icp.genz_icp import GenZICP


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--preset", default="outdoor", help="a GenZ-ICP pre-tuned config name")
    ap.add_argument("--no-deskew", action="store_true")
    ap.add_argument("--max-range", type=float, default=100.0)
    ap.add_argument("--min-range", type=float, default=0.0)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a mapping field of the preset, e.g. voxel_size=1.0")
    args = ap.parse_args()

    config = load_config(Path(args.preset + ".yaml"))
    config.data.deskew = not args.no_deskew
    config.data.max_range = args.max_range
    config.data.min_range = args.min_range
    for kv in args.set:
        key, value = kv.split("=", 1)
        kind = type(getattr(config.mapping, key))
        setattr(config.mapping, key, kind(float(value)) if kind is int else kind(value))
    odom = GenZICP(config)

    frames = sorted((args.data / "velodyne").glob("*.bin"))
    stamps_dir = args.data / "timestamps"
    poses = []
    spent = 0.0
    for f in frames:
        pts = np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        stamps = np.array([])
        s = stamps_dir / f.name
        if config.data.deskew and s.exists():
            t = np.fromfile(s, dtype=np.float64)
            span = t.max() - t.min()
            if span > 0:
                stamps = (t - t.min()) / span - 0.5
        t0 = time.perf_counter()
        odom.register_frame(pts, stamps)
        spent += time.perf_counter() - t0
        poses.append(odom.last_pose[:3].reshape(-1))
    np.savetxt(args.out, np.array(poses), fmt="%.17g")
    print(json.dumps({"frames": len(frames), "seconds": spent, "preset": args.preset,
                      "set": args.set}))


if __name__ == "__main__":
    main()
