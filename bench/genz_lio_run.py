"""A peer of BENCHMARKS.md section 14, "Against LiDAR only and LiDAR-inertial peers" (run by
bench/imu_peers.sh): GenZ-LIO 0.1.1 (PyPI genz-lio) on a `kiss-odom simulate --imu-rate` folder, through its
Python API (`GenZLIO.register_scan`, fed as its own Ouster PCAP reader feeds it): each scan's
points with their times from its first point, the IMU samples since the last scan's end
(t, accel, gyro), and the true extrinsic. Its configuration is its packaged `default/ouster.yaml`
(the simulator writes an Ouster-like 64-beam sweep) with only the extrinsic set from sim.toml
and one thread. The LiDAR pose at each scan's end (its IMU pose times the extrinsic) is written
as poses_kitti.txt relative to the first, with ground_truth.txt, as bench/rko_lio_run.py does.
It expects a still start: a drive that starts turning at ~1 rad/s (drone-1, handheld-1) drifts
in yaw at about that rate from its first scan and diverges.

    python bench/genz_lio_run.py SIM OUT      (a venv with genz-lio==0.1.1 and plyfile)
"""
import sys
import time
import tomllib
import warnings
from importlib.resources import files
from pathlib import Path

import numpy as np
from genz_lio import GenZLIO, load_config

from rko_lio_run import rot_zyx


def kitti(m):
    return " ".join(repr(float(x)) for x in m[:3, :].reshape(-1))


def write_relative(sim, out, poses, summary):
    """poses_kitti.txt (POSES, frame -> world-from-LiDAR 4x4, relative to the first) and
    ground_truth.txt (the same frames of poses.txt, relative to the first), as rko_lio_run.py."""
    gt = [np.vstack([np.array(l.split(), dtype=float).reshape(3, 4), [0, 0, 0, 1]])
          for l in (sim / "poses.txt").read_text().splitlines() if l.strip()]
    ks = sorted(poses)
    if not ks:
        sys.exit(f"{summary}: no poses")
    p0, g0 = np.linalg.inv(poses[ks[0]]), np.linalg.inv(gt[ks[0]])
    (out / "poses_kitti.txt").write_text("".join(kitti(p0 @ poses[k]) + "\n" for k in ks))
    (out / "ground_truth.txt").write_text("".join(kitti(g0 @ gt[k]) + "\n" for k in ks))
    print(summary)


def main():
    sim, out = Path(sys.argv[1]), Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    meta = tomllib.loads((sim / "sim.toml").read_text())["imu"]
    e = meta["lidar_from_imu"]  # the IMU's pose in the LiDAR's frame
    lidar_from_imu = np.eye(4)
    lidar_from_imu[:3, :3] = rot_zyx(*np.radians(e[3:6]))
    lidar_from_imu[:3, 3] = e[:3]
    imu_from_lidar = np.linalg.inv(lidar_from_imu)  # GenZ-LIO's extrinsic: the LiDAR in the IMU
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its YAML's ROS-only `publish`, `pcd_save` sections
        cfg = load_config(str(files("genz_lio") / "configs/default/ouster.yaml"))
    cfg.mapping.extrinsic_r = imu_from_lidar[:3, :3]
    cfg.mapping.extrinsic_t = imu_from_lidar[:3, 3]
    cfg.max_threads = 1
    lio = GenZLIO(cfg)
    imu = np.loadtxt(sim / "imu.csv", delimiter=",", skiprows=1)
    imu[:, 0] -= meta["time_offset"]  # onto the frames' clock
    imu = imu[:, [0, 4, 5, 6, 1, 2, 3]]  # t, accel, gyro
    times = np.loadtxt(sim / "times.txt")
    poses, cursor, started = {}, 0, time.perf_counter()
    for k, end in enumerate(times):
        pts = np.fromfile(sim / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
        st = np.fromfile(sim / "timestamps" / f"{k:06d}.bin", dtype="<f8")
        stop = int(np.searchsorted(imu[:, 0], end, side="right"))
        r = lio.register_scan(pts[:, :3].astype(np.float64), float(st.min()), float(end),
                              imu[cursor:stop], timestamps=st - st.min())
        cursor = stop
        if r.valid:
            poses[k] = r.pose @ imu_from_lidar
    seconds = time.perf_counter() - started
    write_relative(sim, out, poses, f"genz_lio: {len(poses)} poses of {len(times)} "
                   f"frames ({len(times) - len(poses)} without), {seconds:.0f} s")


if __name__ == "__main__":
    main()
