"""Bad input from Python: each case either works as documented in `kiss_odom.odometry` or
raises a clear exception; none crashes the interpreter."""

from __future__ import annotations

import numpy as np
import pytest

import kiss_odom
from conftest import kitti_frames


@pytest.fixture(scope="module")
def scan() -> np.ndarray:
    return next(iter(kitti_frames("05")))


def registered(frame, timestamps=None, warmup=None):
    odom = kiss_odom.KissICP()
    if warmup is not None:
        odom.register_frame(warmup, np.array([]))
    out = odom.register_frame(frame, np.array([]) if timestamps is None else timestamps)
    return odom, out


@pytest.mark.parametrize("columns", [2, 4])
def test_wrong_column_counts_raise_value_errors_naming_the_shape(scan, columns):
    frame = np.zeros((len(scan), columns))
    with pytest.raises(ValueError, match=r"Nx3.*shape \[\d+, %d\]" % columns):
        registered(frame)


def test_a_1d_array_and_a_scalar_raise_value_errors():
    for frame in (np.arange(9.0), 3.0):
        with pytest.raises(ValueError, match="Nx3"):
            registered(frame)


def test_strings_raise_value_errors():
    with pytest.raises(ValueError, match="not an array of numbers"):
        registered(np.array([["a", "b", "c"]]))


def test_float32_is_converted_and_registers_as_its_float64_values(scan):
    f32 = scan.astype(np.float32)
    a, _ = registered(f32)
    b, _ = registered(f32.astype(np.float64))
    assert np.array_equal(a.last_pose, b.last_pose)
    assert a.last_report.input_points == len(scan)


def test_integer_arrays_are_converted(scan):
    ints = np.round(scan).astype(np.int64)
    odom, (frame, _) = registered(ints)
    assert odom.last_report.status == "ok" and frame.dtype == np.float64
    assert np.array_equal(frame, registered(ints.astype(np.float64))[1][0])


def test_non_contiguous_slices_are_copied_and_give_the_same_pose(scan):
    wide = np.zeros((len(scan), 4))
    wide[:, :3] = scan
    strided = wide[:, :3]
    assert not strided.flags["C_CONTIGUOUS"]
    fortran = np.asfortranarray(scan)
    a, _ = registered(strided, warmup=scan)
    b, _ = registered(fortran, warmup=scan)
    c, _ = registered(scan.copy(), warmup=scan)
    assert np.array_equal(a.last_pose, c.last_pose) and np.array_equal(b.last_pose, c.last_pose)


def test_nan_and_inf_rows_are_skipped_counted_and_flagged(scan):
    dirty = scan.copy()
    dirty[::100] = np.nan
    dirty[1::100, 2] = np.inf
    bad = int(np.count_nonzero(~np.isfinite(dirty).all(axis=1)))
    odom, (frame, _) = registered(dirty)
    report = odom.last_report
    assert report.dropped["non_finite"] == bad and "invalid_points" in report.flags
    assert np.isfinite(frame).all() and np.isfinite(odom.last_pose).all()


def test_an_empty_frame_advances_on_the_constant_velocity_model(scan):
    frames = list(kitti_frames("05"))[:3]
    odom = kiss_odom.KissICP()
    for f in frames:
        odom.register_frame(f, np.array([]))
    predicted = odom.last_pose @ odom.last_delta
    for empty in (np.empty((0, 3)), np.array([])):
        frame, source = odom.register_frame(empty, np.array([]))
        assert frame.shape == (0, 3) and source.shape == (0, 3)
        assert odom.last_report.status == "empty"
        assert np.abs(odom.last_pose - predicted).max() < 1e-12
        predicted = odom.last_pose @ odom.last_delta


def test_a_first_frame_of_points_all_out_of_range_is_empty_not_an_error():
    odom = kiss_odom.KissICP()
    odom.register_frame(np.full((10, 3), 1e4), None)
    assert odom.last_report.status == "empty" and np.array_equal(odom.last_pose, np.eye(4))


def test_timestamps_of_the_wrong_length_are_ignored_and_reported(scan):
    odom, _ = registered(scan, timestamps=np.linspace(0, 1, len(scan) - 1))
    report = odom.last_report
    assert report.stamp_problem == "length" and "timestamps_ignored" in report.flags
    assert not report.deskewed
    plain, _ = registered(scan)
    assert np.array_equal(odom.last_pose, plain.last_pose)


def test_constant_and_nan_timestamps_are_ignored_and_reported(scan):
    for stamps, why in ((np.zeros(len(scan)), "constant"),
                        (np.full(len(scan), np.nan), "non_finite")):
        odom, _ = registered(scan, timestamps=stamps)
        assert odom.last_report.stamp_problem == why


def test_timestamps_as_a_column_and_as_none_are_accepted(scan):
    stamps = np.linspace(0.0, 0.1, len(scan))
    odom, _ = registered(scan, timestamps=stamps.reshape(-1, 1), warmup=scan)
    assert odom.last_report.deskewed and odom.last_report.stamp_problem is None
    odom, _ = registered(scan, timestamps=None)
    assert odom.last_report.status == "ok"


def test_backend_inputs_are_checked_too():
    from kiss_odom.backend import kiss_icp_pybind as b

    with pytest.raises(ValueError, match="Nx3"):
        b._Vector3dVector(np.zeros((5, 4)))
    with pytest.raises(ValueError, match="4x4"):
        b._AdaptiveThreshold(2.0, 0.1, 100.0)._update_model_deviation(np.eye(3))
    with pytest.raises(ValueError, match="positive"):
        b._voxel_down_sample(b._Vector3dVector(np.zeros((3, 3))), 0.0)
    with pytest.raises(ValueError, match="N 4x4"):
        b._kitti_seq_error(np.zeros((3, 3)), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="poses"):
        b._absolute_trajectory_error(np.tile(np.eye(4), (3, 1, 1)), np.tile(np.eye(4), (2, 1, 1)))
