"""A peer of BENCHMARKS.md section 15, "Against kiss-icp, GenZ-ICP and MAD-ICP" (run by
bench/accurate.sh through bench/peers.sh): MAD-ICP (PyPI `mad-icp` 0.0.10, built from its sdist)
on a folder in kiss-odom's generic layout or a KITTI `sequences/NN` folder, its poses written in
KITTI format, in the LiDAR's frame.

    madvenv/bin/python bench/mad_run.py DATA OUT.txt [--kitti]

MAD-ICP takes no per-point timestamps: it deskews each sweep with its own velocity estimate
(`deskew` on, as its dataset files set for a moving car) at `sensor_hz` 10. Its parameters are
its `default` set (b_max 0.2, b_min 0.1, b_ratio 0.02, p_th 0.8, rho_ker 0.1, n 10), 4 key
frames, one thread. `--kitti` applies its KITTI reader's elevation correction and range window
(0.7-120 m, no deskew) as its `kitti` dataset file does; otherwise the range window is 0-100 m,
kiss-odom's.

Prints one JSON line: frames, seconds spent in `compute`.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from mad_icp.apps.utils.kitti_reader import KittiReader
from mad_icp.src.pybind.pypeline import Pipeline, VectorEigen3d


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("data", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--kitti", action="store_true")
    args = ap.parse_args()

    velodyne = args.data / "velodyne"
    if args.kitti:
        reader = KittiReader(velodyne, 0.7, 120.0, apply_correction=True, sensor_hz=10)
        deskew = False
    else:
        reader = KittiReader(velodyne, 0.0, 100.0, apply_correction=False, sensor_hz=10)
        deskew = True
    # Pipeline(sensor_hz, deskew, b_max, rho_ker, p_th, b_min, b_ratio, keyframes, cores, realtime)
    pipeline = Pipeline(10, deskew, 0.2, 0.1, 0.8, 0.1, 0.02, 4, 1, False)
    poses = []
    spent = 0.0
    for _ in range(len(reader)):
        ts, points = reader[0]
        t0 = time.perf_counter()
        pipeline.compute(ts, VectorEigen3d(points))
        spent += time.perf_counter() - t0
        poses.append(np.asarray(pipeline.currentPose())[:3].reshape(-1))
    np.savetxt(args.out, np.array(poses), fmt="%.17g")
    print(json.dumps({"frames": len(poses), "seconds": spent}))


if __name__ == "__main__":
    main()
