"""The gyroscope prior through ``KissICP.add_imu``: the same frames and IMU samples give the
same poses, bit for bit, as ``kiss-odom run --imu auto`` (a generated drone flight with an IMU,
``simulate --imu-rate``), a gyroscope in deg/s is rejected with a warning, and the prior is
refused when it is not configured."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import kiss_odom
from conftest import kiss_odom as run_binary, read_kitti


def simulated_flight(tmp_path):
    sim = tmp_path / "sim"
    run_binary("simulate", "--out", sim, "--profile", "drone", "--seed", "41", "--frames", "40",
               "--beams", "32", "--columns", "512", "--imu-rate", "200")
    return sim


def run_with_imu(sim, gyro_scale=1.0):
    """Registers the flight through ``add_imu``, the gyroscope scaled by ``gyro_scale``;
    returns the poses and the frames' ``imu_prior`` states."""
    imu = np.loadtxt(sim / "imu.csv", delimiter=",", skiprows=1)
    # The reader keeps times in whole nanoseconds.
    imu[:, 0] = np.round(imu[:, 0] * 1e9) * 1e-9
    times = np.loadtxt(sim / "times.txt")
    odom = kiss_odom.KissICP({"imu": {"enabled": True}})
    poses, states, j = [], [], 0
    for k, end in enumerate(times):
        pts = np.fromfile(sim / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
        stamps = np.fromfile(sim / "timestamps" / f"{k:06d}.bin", dtype="<f8")
        last = k == len(times) - 1
        while j < len(imu) and (last or imu[j, 0] <= end):
            odom.add_imu(imu[j, 0], imu[j, 1:4] * gyro_scale, imu[j, 4:7])
            j += 1
        odom.register_frame(pts[:, :3].astype(np.float64), stamps)
        poses.append(odom.last_pose)
        states.append(odom.last_report.imu_prior)
    return np.array(poses), states, odom


def test_add_imu_gives_runs_poses_with_the_gyroscope_prior(tmp_path):
    sim = simulated_flight(tmp_path)
    run_binary("run", sim, "--imu", "auto", "--out", tmp_path / "run", "--quiet")
    printed = read_kitti(tmp_path / "run" / "poses_kitti.txt")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ours, states, odom = run_with_imu(sim)
    differ = np.count_nonzero(ours[:, :3, :] != printed[:, :3, :])
    print(f"drone, 40 frames with the prior: {differ} pose entries differ from run's "
          f"(allowed 0), worst {np.abs(ours - printed).max():.1e}; bias {odom.gyro_bias}")
    assert states[0] == "first" and all(s == "used" for s in states[1:]), states
    assert differ == 0


def test_a_gyroscope_in_degrees_per_second_is_rejected_with_a_warning(tmp_path):
    sim = simulated_flight(tmp_path)
    with pytest.warns(RuntimeWarning, match="degrees per second") as caught:
        _, states, _ = run_with_imu(sim, gyro_scale=180.0 / np.pi)
    rejected = states.count("rejected")
    print(f"drone, gyro in deg/s: {rejected} of {len(states)} frames rejected, "
          f"{len(caught)} warning(s)")
    assert rejected >= len(states) - 2, states
    assert "used" not in states, states
    assert len(caught) == 1


def test_add_imu_without_the_prior_is_refused():
    odom = kiss_odom.KissICP()
    with pytest.raises(ValueError, match="imu.enabled"):
        odom.add_imu(0.0, [0.0, 0.0, 0.0], [0.0, 0.0, 9.8])
    assert odom.gyro_bias is None
    on = kiss_odom.KissICP({"imu": {"enabled": True}})
    with pytest.raises(ValueError, match="three"):
        on.add_imu(0.0, [0.0, 0.0], [0.0, 0.0, 9.8])
    assert list(on.gyro_bias) == [0.0, 0.0, 0.0]
