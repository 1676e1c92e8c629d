"""Localization in a prior map through ``KissICP(map=..., initial_pose=...)``: on a generated
revisit (``simulate --revisit``, the map built from the first drive's poses) the map-frame
poses are those of ``kiss-odom run --map --initial-pose``, bit for bit, and within half a metre
of the truth; the odometry's own poses are unchanged by the map; a map without a start, a start
without a map and a map that cannot be used are ``ValueError``s naming why; damaged tiles
warn once."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import kiss_odom
from conftest import kiss_odom as run_binary, read_kitti

#: Largest distance (m) from the truth allowed on the revisit's last frames.
TRUTH_TOLERANCE = 0.5
#: Largest difference allowed from ``run``'s poses when the start is given as a 4x4 matrix
#: (the text form is read by ``run``'s parser, the matrix form converted to a quaternion).
MATRIX_TOLERANCE = 1e-9


@pytest.fixture(scope="module")
def revisit(tmp_path_factory) -> dict:
    """A drive A, its revisit B (the same route the other way through a changed scene), a map
    built from A's true poses and ``run``'s localization of B in it."""
    root = tmp_path_factory.mktemp("revisit")
    first, again = root / "A", root / "B"
    flags = ("--frames", 60, "--profile", "urban", "--seed", 3)
    run_binary("simulate", *flags, "--out", first)
    run_binary("simulate", *flags, "--revisit", "--out", again)
    site = root / "site.komap"
    run_binary("map", "build", first, "--poses", first / "poses.txt", "--out", site)
    start = (again / "initial_pose.txt").read_text().strip()
    run_binary("run", again, "--map", site, "--initial-pose", start, "--out", root / "run",
               "--quiet")
    return {
        "B": again,
        "map": site,
        "start": start,
        "run": read_kitti(root / "run" / "poses_kitti.txt"),
        "truth": read_kitti(again / "poses.txt"),
    }


def frames(sequence: Path):
    """The generic layout's frames: points (float32 x, y, z, i) and per-point times."""
    for k in range(len(np.loadtxt(sequence / "times.txt", ndmin=1))):
        pts = np.fromfile(sequence / "velodyne" / f"{k:06d}.bin", dtype="<f4").reshape(-1, 4)
        stamps = np.fromfile(sequence / "timestamps" / f"{k:06d}.bin", dtype="<f8")
        yield pts[:, :3].astype(np.float64), stamps


def drive(odom: kiss_odom.KissICP, sequence: Path):
    """Registers every frame; returns the odometry's poses, the map-frame poses and the
    reports."""
    own, in_map, reports = [], [], []
    for pts, stamps in frames(sequence):
        odom.register_frame(pts, stamps)
        own.append(odom.last_pose)
        in_map.append(odom.map_pose)
        reports.append(odom.last_report)
    return np.array(own), in_map, reports


def matrix_of_xyz_rpy(text: str) -> np.ndarray:
    """``X,Y,Z,ROLL,PITCH,YAW`` (m, degrees) as 4x4, ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    x, y, z, *rpy = map(float, text.split(","))
    r, p, w = np.radians(rpy)
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rz = np.array([[np.cos(w), -np.sin(w), 0], [np.sin(w), np.cos(w), 0], [0, 0, 1]])
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = rz @ ry @ rx, (x, y, z)
    return m


def test_map_poses_are_run_s_map_poses_bit_for_bit(revisit):
    odom = kiss_odom.KissICP(map=revisit["map"], initial_pose=revisit["start"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _, in_map, reports = drive(odom, revisit["B"])
    ours, printed = np.array(in_map), revisit["run"]
    differ = np.count_nonzero(ours[:, :3, :] != printed[:, :3, :])
    print(f"revisit, {len(ours)} frames in the map: {differ} pose entries differ from "
          f"run --map's (allowed 0), worst {np.abs(ours - printed).max():.1e}")
    assert differ == 0
    assert all(r.localization in ("localized", "degraded", "lost") for r in reports)

    start = matrix_of_xyz_rpy(revisit["start"])
    as_matrix = kiss_odom.KissICP(map=revisit["map"], initial_pose=start)
    _, in_map, _ = drive(as_matrix, revisit["B"])
    worst = np.abs(np.array(in_map) - printed).max()
    print(f"revisit, the start as a 4x4 matrix: worst difference from run --map's {worst:.1e} "
          f"(allowed {MATRIX_TOLERANCE:.0e})")
    assert worst <= MATRIX_TOLERANCE


def test_the_revisit_is_localized_within_half_a_metre_of_the_truth(revisit):
    odom = kiss_odom.KissICP(map=revisit["map"], initial_pose=revisit["start"])
    own, in_map, reports = drive(odom, revisit["B"])
    truth = revisit["truth"]
    error = np.linalg.norm(np.array(in_map)[:, :3, 3] - truth[:, :3, 3], axis=1)
    states = [r.localization for r in reports]
    localized = states.count("localized")
    last = error[-10:].max()
    print(f"revisit: last 10 frames at most {last:.3f} m from the truth (allowed "
          f"{TRUTH_TOLERANCE} m), worst over all {error.max():.3f} m; {localized} of "
          f"{len(states)} frames localized (need 80 %), states {sorted(set(states))}; "
          f"last inlier share {reports[-1].map_inlier_share:.2f}, correction "
          f"{reports[-1].map_correction_m:.3f} m")
    assert last <= TRUTH_TOLERANCE
    assert localized >= 0.8 * len(states)
    assert "lost" not in states

    # The odometry's own poses are those of a run without a map, bit for bit.
    alone, no_map, no_reports = drive(kiss_odom.KissICP(), revisit["B"])
    differ = np.count_nonzero(own != alone)
    print(f"revisit: {differ} entries of last_pose differ with the map from without (allowed 0)")
    assert differ == 0
    assert no_map[-1] is None and no_reports[-1].localization is None
    assert no_reports[-1].map_inlier_share is None and no_reports[-1].map_correction_m is None


def test_reset_localizes_from_the_initial_pose_again(revisit):
    odom = kiss_odom.KissICP(map=revisit["map"], initial_pose=revisit["start"])
    assert odom.map_pose is None
    _, first, _ = drive(odom, revisit["B"])
    odom.reset()
    assert odom.map_pose is None
    _, again, _ = drive(odom, revisit["B"])
    differ = np.count_nonzero(np.array(first) != np.array(again))
    print(f"revisit after reset(): {differ} map-pose entries differ from the first pass "
          f"(allowed 0)")
    assert differ == 0


def test_a_map_needs_a_start_and_a_start_needs_a_map(revisit):
    with pytest.raises(ValueError, match="not searched for over the whole map"):
        kiss_odom.KissICP(map=revisit["map"])
    with pytest.raises(ValueError, match="needs map"):
        kiss_odom.KissICP(initial_pose=np.eye(4))
    with pytest.raises(ValueError, match="six"):
        kiss_odom.KissICP(map=revisit["map"], initial_pose="1,2,3")
    with pytest.raises(ValueError, match="rigid"):
        kiss_odom.KissICP(map=revisit["map"], initial_pose=2 * np.eye(4))


def test_a_map_that_cannot_be_used_is_refused_naming_why(revisit, tmp_path):
    start = revisit["start"]
    short = tmp_path / "short.komap"
    short.write_bytes(revisit["map"].read_bytes()[:5000])
    with pytest.raises(ValueError, match="truncated") as caught:
        kiss_odom.KissICP(map=short, initial_pose=start)
    print(f"truncated map: {caught.value}")
    assert str(short) in str(caught.value)
    with pytest.raises(ValueError, match="voxel size") as caught:
        kiss_odom.KissICP({"mapping": {"voxel_size": 0.7}}, map=revisit["map"], initial_pose=start)
    print(f"another voxel size: {caught.value}")
    with pytest.raises(ValueError, match="another frame"):
        kiss_odom.KissICP({"output": {"map_frame": "odom"}}, map=revisit["map"], initial_pose=start)
    site = tmp_path / "site.komap"
    sequence = revisit["B"].parent / "A"
    run_binary("map", "build", sequence, "--poses", sequence / "poses.txt", "--frame", "site",
               "--out", site)
    with pytest.raises(ValueError, match="another frame") as caught:
        kiss_odom.KissICP(map=site, initial_pose=start)
    print(f"another frame: {caught.value}")
    kiss_odom.KissICP({"output": {"map_frame": "site"}}, map=site, initial_pose=start)
    with pytest.raises(ValueError, match="cannot read"):
        kiss_odom.KissICP(map=tmp_path / "none.komap", initial_pose=start)


def test_damaged_tiles_warn_once_as_a_runtime_warning(revisit, tmp_path):
    data = bytearray(revisit["map"].read_bytes())
    tiles = int.from_bytes(data[40:44], "little")
    capacity = int.from_bytes(data[36:40], "little")
    records = 128 + 12 * tiles
    # One bit of each record's first point: every tile's CRC fails but the first's.
    for t in range(1, tiles):
        data[records + t * (16 + 12 * capacity) + 16] ^= 1
    damaged = tmp_path / "damaged.komap"
    damaged.write_bytes(bytes(data))
    odom = kiss_odom.KissICP(map=damaged, initial_pose=revisit["start"])
    with pytest.warns(RuntimeWarning, match="damaged tile") as caught:
        drive(odom, revisit["B"])
    said = [w for w in caught if "damaged tile" in str(w.message)]
    print(f"{tiles - 1} of {tiles} tiles damaged: {len(said)} warning(s) (allowed 1): "
          f"{said[0].message}")
    assert len(said) == 1
