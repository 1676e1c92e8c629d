#!/usr/bin/env python3
"""kiss-icp 1.3.0's peak resident memory on a folder of frames, streamed as its own pipeline
streams them (one frame in memory at a time): prints the peak RSS in bytes. Used by
bench/map_bound.py for the reference's column of "The host's map never evicts".

    python bench/kiss_icp_rss.py FOLDER MAX_RANGE VOXEL_SIZE [POSES_OUT]

FOLDER: a generic (velodyne/*.bin float32 x y z i, optional timestamps/*.bin float64) or KITTI
layout folder. POSES_OUT, if given, receives kiss-icp's pose of every frame (KITTI rows, full
precision), so one streamed pass also gives the reference's trajectory on a recording too large
for the in-memory crosscheck. Runs in the kiss-icp venv (tests/reference/requirements.txt).
"""

import resource
import sys
from pathlib import Path

import numpy as np
from kiss_icp.config import load_config
from kiss_icp.kiss_icp import KissICP


def main():
    folder, max_range, voxel = Path(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
    config = load_config(None)
    config.data.max_range = max_range
    config.mapping.voxel_size = voxel
    config.registration.max_num_threads = 1
    odom = KissICP(config)
    rows = []
    for scan in sorted((folder / "velodyne").glob("*.bin")):
        points = np.fromfile(scan, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        stamps = folder / "timestamps" / scan.name
        times = np.fromfile(stamps, dtype=np.float64) if stamps.exists() else np.array([])
        if len(times) != len(points):
            times = np.array([])
        odom.register_frame(points, times)
        rows.append(" ".join(repr(float(v)) for v in odom.last_pose[:3, :].reshape(-1)))
    if len(sys.argv) > 4:
        Path(sys.argv[4]).write_text("\n".join(rows) + "\n")
    print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)


if __name__ == "__main__":
    main()
