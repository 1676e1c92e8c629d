"""A peer of BENCHMARKS.md section 14, "Against LiDAR only and LiDAR-inertial peers" (run by
bench/imu_peers.sh): pelorus 0.0.8 (PyPI) on a `kiss-odom simulate --imu-rate` folder, through its Python API
(`pelorus.Handle`): the IMU samples up to 10 ms past each scan's end (`add_imu`, no
orientation), then the scan as [x, y, z, t] with t the points' ns after its first
(`add_pointcloud`, stamped with that first point's time), waiting for its odometry before the
next scan (its queue drops scans fed faster than it runs). Its embedded default configuration,
with only: the extrinsic from sim.toml (`imu.from_lidar_transform`: LiDAR into IMU), the
points' time layout (`lidar.vendor = Ouster`, per-point ns offsets; the default NoTimestamp
does not deskew), one thread, no terminal UI. Extra settings can be given as ratslang lines
after OUT (e.g. `imu.calibration.gyroscope = false`). It expects a still start (its
`imu.initial_setup`): a drive that starts turning at ~1 rad/s (drone-1, handheld-1) diverges,
with or without `imu.calibration.gyroscope = false`.

Each scan's odometry is stamped with the last IMU sample before the scan's end (up to 5 ms
before it), but is the LiDAR's pose at the scan's end (on urban-1, against the ground truth
5 ms earlier, its ATE is 0.034 m against 0.028 m at the end): it is written as that scan's.
Its poses as reported are kept in pelorus_tum.txt; those per scan and the ground truth are
written as bench/rko_lio_run.py writes them. All times are moved by 1.7e9 s.

    python bench/pelorus_run.py SIM OUT [SETTING...]   (a venv with pelorus==0.0.8, genz-lio)
"""
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pelorus

from genz_lio_run import write_relative
from rko_lio_run import EPOCH, quat_to_matrix, rot_zyx


def stamp(t):
    ns = round((t + EPOCH) * 1e9)
    return ns // 10**9, ns % 10**9


def main():
    sim, out = Path(sys.argv[1]), Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    meta = tomllib.loads((sim / "sim.toml").read_text())["imu"]
    e = meta["lidar_from_imu"]
    lidar_from_imu = np.eye(4)
    lidar_from_imu[:3, :3] = rot_zyx(*np.radians(e[3:6]))
    lidar_from_imu[:3, 3] = e[:3]
    m = np.linalg.inv(lidar_from_imu)  # pelorus's extrinsic: LiDAR coordinates into the IMU's
    rows = ", ".join("[" + ", ".join(repr(float(v)) for v in r) + "]" for r in m[:3, :3])
    (out / "pelorus.rl").write_text(
        "lidar.vendor = Ouster\nparallelism.num_threads = 1\noutput.terminal.ui = false\n"
        "imu.from_lidar_transform.translation = [" + ", ".join(f"{float(v)!r}m" for v in m[:3, 3]) + "]\n"
        f"imu.from_lidar_transform.rotation = [{rows}]\n" + "".join(a + "\n" for a in sys.argv[3:]))
    lio = pelorus.Handle(str(out / "pelorus.rl"))
    imu = np.loadtxt(sim / "imu.csv", delimiter=",", skiprows=1)
    imu[:, 0] -= meta["time_offset"]  # onto the frames' clock
    times = np.loadtxt(sim / "times.txt")
    got, cursor, started = [], 0, time.perf_counter()
    for k, end in enumerate(times):
        pts = np.fromfile(sim / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
        st = np.fromfile(sim / "timestamps" / f"{k:06d}.bin", dtype="<f8")
        while cursor < len(imu) and imu[cursor, 0] <= end + 0.01:
            r = imu[cursor]
            lio.add_imu(*stamp(r[0]), [1.0, 0.0, 0.0, 0.0], [0.0] * 9, list(r[1:4]), [0.0] * 9,
                        list(r[4:7]), [0.0] * 9)
            cursor += 1
        cloud = np.column_stack([pts[:, :3], np.round((st - st.min()) * 1e9)])
        lio.add_pointcloud(cloud, *stamp(st.min()))
        wait = time.perf_counter() + 5.0  # the first scans build the map and give no odometry
        while time.perf_counter() < wait:
            o = lio.try_recv()
            if o is None:
                time.sleep(0.002)
                continue
            got.append(o)
            if o["timestamp_sec"] + o["timestamp_nanosec"] * 1e-9 - EPOCH > st.min():
                break
    time.sleep(2.0)
    while (o := lio.try_recv()) is not None:
        got.append(o)
    seconds = time.perf_counter() - started
    poses, tum = {}, []
    for o in got:
        t = o["timestamp_sec"] + o["timestamp_nanosec"] * 1e-9 - EPOCH
        k = int(np.searchsorted(times, t - 1e-6))  # the first scan ending at or after it
        p = np.eye(4)
        w, x, y, z = o["orientation"]
        p[:3, :3] = quat_to_matrix(x, y, z, w)
        p[:3, 3] = o["position"]
        tum.append(" ".join(repr(float(v)) for v in [t, *o["position"], x, y, z, w]))
        if k < len(times) and times[k] - t < 0.0101:
            poses[k] = p
    (out / "pelorus_tum.txt").write_text("".join(l + "\n" for l in tum))  # as it reported them
    write_relative(sim, out, poses, f"pelorus: {len(poses)} poses of {len(times)} frames "
                   f"({len(times) - len(poses)} without), {seconds:.0f} s")


if __name__ == "__main__":
    main()
