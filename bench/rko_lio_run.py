"""A peer of BENCHMARKS.md section 14, "Against LiDAR only and LiDAR-inertial peers" (run by
bench/imu_peers.sh): rko_lio 0.4.0 (PyPI, the same lab's LiDAR-inertial odometry) on a `kiss-odom simulate
--imu-rate` folder: the frames and IMU samples written in rko_lio's raw layout (one PLY per scan
named by its end time in ns, with per-point times; imu.csv in ns; transforms.yaml with the
LiDAR as the base and the IMU at sim.toml's extrinsic), rko_lio's CLI run on it, and its
trajectory written back as poses_kitti.txt, one pose per frame at the scan's end, relative to
the first (frames it gives no pose for are reported and left out of ground_truth.txt too).

    python bench/rko_lio_run.py SIM OUT      (the Python of a venv with rko-lio==0.4.0, plyfile)

All times are moved by 1.7e9 s, a present-day clock, so rko_lio's unit detection sees what a
sensor sends.
"""
import math
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
from plyfile import PlyData, PlyElement

EPOCH = 1_700_000_000.0


def rot_zyx(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def quat_to_matrix(qx, qy, qz, qw):
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])


def main():
    sim, out = Path(sys.argv[1]), Path(sys.argv[2])
    meta = tomllib.loads((sim / "sim.toml").read_text())["imu"]
    raw = out / "raw"
    shutil.rmtree(raw, ignore_errors=True)
    (raw / "lidar").mkdir(parents=True)
    times = np.loadtxt(sim / "times.txt")
    for k, end in enumerate(times):
        pts = np.fromfile(sim / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
        st = np.fromfile(sim / "timestamps" / f"{k:06d}.bin", dtype="<f8")
        v = np.empty(len(pts), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("time", "f8")])
        v["x"], v["y"], v["z"], v["time"] = pts[:, 0], pts[:, 1], pts[:, 2], st + EPOCH
        ns = round((end + EPOCH) * 1e9)
        PlyData([PlyElement.describe(v, "vertex")], byte_order="<").write(str(raw / "lidar" / f"{ns}.ply"))
    imu = np.loadtxt(sim / "imu.csv", delimiter=",", skiprows=1)
    with open(raw / "imu.csv", "w") as f:
        f.write("timestamp,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n")
        for r in imu:
            f.write(f"{round((r[0] - meta['time_offset'] + EPOCH) * 1e9)}," + ",".join(repr(float(x)) for x in r[1:]) + "\n")
    e = meta["lidar_from_imu"]
    t_imu = np.eye(4)
    t_imu[:3, :3] = rot_zyx(*np.radians(e[3:6]))
    t_imu[:3, 3] = e[:3]
    with open(raw / "transforms.yaml", "w") as f:
        f.write(f"T_imu_to_base: {t_imu.tolist()}\nT_lidar_to_base: {np.eye(4).tolist()}\n")
    rko = Path(sys.executable).parent / "rko_lio"
    subprocess.run([str(rko), "-d", "raw", str(raw), "-o", str(out / "log"), "-n", "run"],
                   check=True, stdout=subprocess.DEVNULL)
    tum = np.loadtxt(next((out / "log").rglob("*_tum.txt")))
    gt = [l for l in (sim / "poses.txt").read_text().splitlines() if l.strip()]
    rows, truth, missing = [], [], 0
    first = None
    for k, end in enumerate(times):
        # The file's times have 6 decimals of a 1.7e9 s clock: the scan's within 5 us.
        i = int(np.argmin(np.abs(tum[:, 0] - (end + EPOCH))))
        t = tum[i] if abs(tum[i, 0] - (end + EPOCH)) < 5e-6 else None
        if t is None:
            missing += 1
            continue
        p = np.eye(4)
        p[:3, :3] = quat_to_matrix(*t[4:8])
        p[:3, 3] = t[1:4]
        if first is None:
            first = np.linalg.inv(p)
            g0 = np.eye(4)
            g0[:3, :] = np.array(gt[k].split(), dtype=float).reshape(3, 4)
            g0_inv = np.linalg.inv(g0)
        rel = first @ p
        rows.append(" ".join(repr(float(x)) for x in rel[:3, :].reshape(-1)))
        g = np.eye(4)
        g[:3, :] = np.array(gt[k].split(), dtype=float).reshape(3, 4)
        truth.append(" ".join(repr(float(x)) for x in (g0_inv @ g)[:3, :].reshape(-1)))
    (out / "poses_kitti.txt").write_text("\n".join(rows) + "\n")
    (out / "ground_truth.txt").write_text("\n".join(truth) + "\n")
    print(f"rko_lio: {len(rows)} poses of {len(times)} frames ({missing} without)")


if __name__ == "__main__":
    main()
