"""A gyro prior for KISS-ICP, measured before it goes into the core: each sweep's relative
motion (the constant-velocity model `last_delta`, which deskews the sweep and predicts its pose)
gets its rotation from the gyroscope integrated over the sweep (end of the last to end of this),
minus a bias estimated from how the registered rotation disagreed with the gyro's, and keeps
the constant-velocity translation. Run through kiss-odom's Python drop-in (`KissICP`), whose
`last_delta` is assignable as kiss-icp's is; with `--off` the same loop without the prior.

    python bench/imu_prior_proto.py DIR OUT [--off] [--bias-gain 0.1]

DIR: a `kiss-odom simulate --imu-rate ...` folder (frames, timestamps, imu.csv, sim.toml).
Writes OUT/poses_kitti.txt.
"""
import argparse
import os
import tomllib

import numpy as np
from kiss_odom import KissICP


def so3_exp(w):
    th = np.linalg.norm(w)
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    if th < 1e-12:
        return np.eye(3) + k
    return np.eye(3) + np.sin(th) / th * k + (1 - np.cos(th)) / th**2 * k @ k


def so3_log(r):
    c = np.clip((np.trace(r) - 1) / 2, -1, 1)
    th = np.arccos(c)
    w = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    s = np.linalg.norm(w)
    return w if s < 1e-12 else w * th / s


def rotz_y_x(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def integrate(imu, t0, t1, bias):
    """Rotation from t0 to t1 (body frame at t0 to t1), piecewise-constant rate at each sample."""
    t, w = imu[:, 0], imu[:, 1:4]
    r = np.eye(3)
    i = max(np.searchsorted(t, t0, side="right") - 1, 0)
    a = t0
    while a < t1 and i < len(t):
        b = min(t[i + 1] if i + 1 < len(t) else t1, t1)
        if b > a:
            r = r @ so3_exp((w[i] - bias) * (b - a))
        a = b
        i += 1
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("out")
    ap.add_argument("--off", action="store_true")
    ap.add_argument("--bias-gain", type=float, default=0.1)
    ap.add_argument("--no-deskew", action="store_true")
    a = ap.parse_args()
    meta = tomllib.load(open(os.path.join(a.dir, "sim.toml"), "rb"))
    e = meta["imu"]["lidar_from_imu"]
    r_li = rotz_y_x(*np.radians(e[3:6]))
    imu = np.loadtxt(os.path.join(a.dir, "imu.csv"), delimiter=",", skiprows=1)
    imu[:, 0] -= meta["imu"]["time_offset"]
    times = np.loadtxt(os.path.join(a.dir, "times.txt"))
    odom = KissICP({"data": {"deskew": not a.no_deskew, "max_range": 100.0, "min_range": 0.0}})
    bias = np.zeros(3)
    poses = []
    for k in range(len(times)):
        pts = np.fromfile(os.path.join(a.dir, "velodyne", f"{k:06d}.bin"), dtype="<f4").reshape(-1, 4)
        st = np.fromfile(os.path.join(a.dir, "timestamps", f"{k:06d}.bin"), dtype="<f8")
        gyro = None
        if not a.off and k >= 1:
            # IMU axes to LiDAR axes: R_LI R_I R_LI^T.
            gyro = r_li @ integrate(imu, times[k - 1], times[k], bias) @ r_li.T
            delta = odom.last_delta.copy()
            delta[:3, :3] = gyro
            odom.last_delta = delta
        odom.register_frame(pts[:, :3].astype(np.float64), st)
        if gyro is not None and k >= 2:
            # The registered rotation against the gyro's: a rate error to take from the bias.
            measured = odom.last_delta[:3, :3]
            err = r_li.T @ so3_log(gyro.T @ measured) / (times[k] - times[k - 1])
            bias -= a.bias_gain * err
        poses.append(odom.last_pose[:3, :].reshape(-1))
    os.makedirs(a.out, exist_ok=True)
    np.savetxt(os.path.join(a.out, "poses_kitti.txt"), np.array(poses), fmt="%.17g")
    print(f"bias estimate {bias} (turn-on {meta['imu']['gyro_bias_turn_on']})")


if __name__ == "__main__":
    main()
