"""`kiss_odom.KissICP` against `kiss-odom run` (bit for bit) and against kiss-icp 1.3.0's own
`KissICP` in the same process (to 1e-9 m), and its kiss-icp-shaped surface."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import kiss_odom
from conftest import KITTI_SEQUENCES, kiss_odom as run_binary, kitti_frames, kitti_root, read_kitti

TOL_REFERENCE_M = 1e-9


def our_poses(frames, **kwargs) -> np.ndarray:
    odom = kiss_odom.KissICP(**kwargs)
    poses = []
    for f in frames:
        odom.register_frame(f, np.array([]))
        poses.append(odom.last_pose)
    return np.array(poses)


@pytest.mark.parametrize("sequence", KITTI_SEQUENCES)
def test_poses_are_bit_identical_to_kiss_odom_run(sequence, tmp_path):
    run_binary("run", kitti_root() / "sequences" / sequence, "--out", tmp_path, "--quiet")
    printed = read_kitti(tmp_path / "poses_kitti.txt")
    ours = our_poses(kitti_frames(sequence))
    assert ours.shape == printed.shape
    differ = np.count_nonzero(ours[:, :3, :] != printed[:, :3, :])
    print(f"{sequence}: {differ} of {printed[:, :3, :].size} pose entries differ from run's "
          f"poses_kitti.txt (allowed 0), worst {np.abs(ours - printed).max():.1e}")
    assert differ == 0


def test_the_accurate_preset_is_run_s_accurate_preset_bit_for_bit(tmp_path):
    sequence = KITTI_SEQUENCES[0]
    frames = list(kitti_frames(sequence))[:6]
    out = tmp_path / "run"
    run_binary("run", kitti_root() / "sequences" / sequence, "--out", out, "--quiet",
               "--preset", "accurate", "--frames", f"..{len(frames)}")
    printed = read_kitti(out / "poses_kitti.txt")
    odom = kiss_odom.KissICP(preset="accurate")
    assert odom.settings["pipeline"]["preset"] == "accurate"
    assert odom.settings["registration"]["degeneracy"] == "robust"
    poses, planar = [], []
    for f in frames:
        odom.register_frame(f, np.array([]))
        poses.append(odom.last_pose)
        planar.append(odom.last_report.plane_correspondences)
    ours = np.array(poses)
    differ = np.count_nonzero(ours[:, :3, :] != printed[:, :3, :])
    print(f"accurate, {sequence}: {differ} of {printed[:, :3, :].size} pose entries differ from "
          f"run --preset accurate (allowed 0); point-to-plane terms per frame {planar}")
    assert differ == 0
    assert planar[0] == 0 and min(planar[1:]) > 0
    # Without the preset the same frames give other poses (the default is kiss-icp's).
    assert not np.array_equal(our_poses(frames), ours)
    # A value the config gives wins over the preset's; a preset nobody knows is refused.
    given = kiss_odom.KissICP({"mapping": {"voxel_size": 0.7}}, preset="accurate")
    assert given.settings["mapping"]["voxel_size"] == 0.7
    with pytest.raises(ValueError, match="preset"):
        kiss_odom.KissICP(preset="fastest")


def _translation_gap(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a[:, :3, 3] - b[:, :3, 3], axis=1).max())


def _rotation_gap(a: np.ndarray, b: np.ndarray) -> float:
    # atan2 of the skew part: arccos of the trace loses half the digits near zero.
    rel = np.einsum("nji,njk->nik", a[:, :3, :3], b[:, :3, :3])
    skew = np.stack([rel[:, 2, 1] - rel[:, 1, 2], rel[:, 0, 2] - rel[:, 2, 0],
                     rel[:, 1, 0] - rel[:, 0, 1]], axis=1)
    sin = np.linalg.norm(skew, axis=1) / 2
    cos = (np.trace(rel, axis1=1, axis2=2) - 1) / 2
    return float(np.arctan2(sin, cos).max())


@pytest.mark.parametrize("sequence", KITTI_SEQUENCES)
def test_poses_agree_with_kiss_icp_in_the_same_process(sequence):
    kiss_icp = pytest.importorskip("kiss_icp.kiss_icp", reason="SKIP: kiss-icp not installed")
    from kiss_icp.config import load_config

    frames = list(kitti_frames(sequence))
    config = load_config(None)
    ref = kiss_icp.KissICP(config)
    want = []
    for f in frames:
        ref.register_frame(f, np.array([]))
        want.append(ref.last_pose)
    want = np.array(want)
    ours = our_poses(frames, config=config)
    dt, dr = _translation_gap(ours, want), _rotation_gap(ours, want)
    print(f"{sequence}: worst {dt:.2e} m, {dr:.2e} rad from kiss-icp 1.3.0 "
          f"(allowed {TOL_REFERENCE_M:.0e})")
    assert dt <= TOL_REFERENCE_M and dr <= TOL_REFERENCE_M


def test_returns_the_deskewed_frame_and_the_source_like_kiss_icp():
    kiss_icp = pytest.importorskip("kiss_icp.kiss_icp", reason="SKIP: kiss-icp not installed")
    from kiss_icp.config import load_config

    frames = list(kitti_frames("05"))[:3]
    ref, ours = kiss_icp.KissICP(load_config(None)), kiss_odom.KissICP()
    for f in frames:
        ref_frame, ref_source = ref.register_frame(f, np.array([]))
        frame, source = ours.register_frame(f, np.array([]))
        assert frame.shape == ref_frame.shape and source.shape == ref_source.shape
        worst = max(np.abs(frame - ref_frame).max(), np.abs(source - ref_source).max())
        print(f"deskewed frame and source: worst {worst:.1e} m (allowed {TOL_REFERENCE_M:.0e})")
        assert worst <= TOL_REFERENCE_M


def test_every_configuration_form_gives_the_same_settings(tmp_path):
    pytest.importorskip("kiss_icp.config", reason="SKIP: kiss-icp not installed")
    from kiss_icp.config import load_config

    yaml_file = tmp_path / "kiss.yaml"
    yaml_file.write_text("data:\n  max_range: 60.0\nmapping:\n  max_points_per_voxel: 10\n")
    forms = {
        "KISSConfig": load_config(yaml_file),
        "YAML path": yaml_file,
        "dict": {"data": {"max_range": 60.0}, "mapping": {"max_points_per_voxel": 10,
                                                          "voxel_size": 0.6}},
    }
    odoms = {name: kiss_odom.KissICP(c) for name, c in forms.items()}
    toml_file = tmp_path / "config.toml"
    toml_file.write_text(odoms["dict"].settings_toml())
    odoms["config.toml"] = kiss_odom.KissICP(toml_file)
    first = odoms["dict"]
    assert first.settings["data"]["max_range"] == 60.0
    assert first.settings["mapping"]["max_points_per_voxel"] == 10
    # As run and as given: the same settings. No capacity is named, so none is written out
    # (they grow with the map as run's do), and a run from config.toml grows too.
    for name, o in odoms.items():
        assert o.settings_toml() == first.settings_toml(), f"{name}: {o.settings_toml()}"
        assert o.settings == first.settings, f"{name}: {json.dumps(o.settings)}"
    assert "map_voxels" not in first.settings_toml()
    assert not odoms["config.toml"].settings.get("capacities")
    # kiss-icp's pipeline reads its own config object back.
    assert kiss_odom.KissICP(forms["KISSConfig"]).config is forms["KISSConfig"]


def test_extras_pick_the_build_and_bad_settings_name_themselves():
    frames = list(kitti_frames("05"))[:4]
    ref = our_poses(frames)
    for scalar, storage in (("f32", "exact"), ("f64", "quantized"), ("f32", "quantized")):
        poses = our_poses(frames, scalar=scalar, map_storage=storage, capacities="full")
        gap = _translation_gap(poses, ref)
        print(f"{scalar}/{storage}: {gap:.2e} m from f64/exact after {len(frames)} frames")
        assert 0 < gap < 0.05
    odom = kiss_odom.KissICP(capacities="small", threads=1)
    assert odom.settings["capacities"]["map_voxels"] == 8192
    assert odom.state_bytes < kiss_odom.KissICP().state_bytes
    with pytest.raises(ValueError, match="max_rnage"):
        kiss_odom.KissICP({"data": {"max_rnage": 3.0}})
    with pytest.raises(ValueError, match="fixed_threshold"):
        kiss_odom.KissICP({"adaptive_threshold": {"fixed_threshold": 1.0}})
    with pytest.raises(ValueError, match="max_range"):
        kiss_odom.KissICP({"data": {"max_range": -1.0}})
    with pytest.raises(ValueError, match="scalar"):
        kiss_odom.KissICP(scalar="f16")


def test_pose_and_velocity_are_assignable_and_the_map_clears_like_kiss_icp():
    frames = list(kitti_frames("05"))
    odom = kiss_odom.KissICP()
    assert odom.local_map.empty()
    for f in frames[:3]:
        odom.register_frame(f, np.array([]))
    assert not odom.local_map.empty()
    cloud = odom.local_map.point_cloud()
    assert cloud.ndim == 2 and cloud.shape[1] == 3 and len(cloud) == odom.last_report.map_points
    # kiss-icp: an empty map registers nothing, so the pose is the prediction last_pose @ delta.
    start = np.eye(4)
    start[:3, 3] = [10.0, -5.0, 2.0]
    odom.last_pose, odom.last_delta = start, np.eye(4)
    odom.local_map.clear()
    assert odom.local_map.empty()
    odom.register_frame(frames[3], np.array([]))
    assert np.array_equal(odom.last_pose, start)
    with pytest.raises(ValueError, match="rigid"):
        odom.last_pose = np.full((4, 4), 2.0)
    with pytest.raises(ValueError, match="4x4"):
        odom.last_delta = np.eye(3)


def test_the_report_names_flags_and_counts():
    odom = kiss_odom.KissICP()
    frames = list(kitti_frames("05"))[:2]
    odom.register_frame(frames[0], np.array([]))
    first = odom.last_report
    assert first.index == 0 and first.status == "ok" and first.ok
    assert first.input_points == len(frames[0]) and first.map_points > 0
    assert first.observability is None and not first.deskewed
    odom.register_frame(frames[1], np.array([]))
    second = odom.last_report
    assert second.index == 1 and second.iterations > 0 and second.correspondences > 0
    assert second.sigma == pytest.approx(2.0) and second.observability is not None
    assert set(second.dropped) == {"non_finite", "truncated", "merge_full", "source_full",
                                   "map_voxels_full", "map_points_full"}


def test_the_thread_count_does_not_change_a_bit():
    frames = list(kitti_frames("05"))
    one, two = our_poses(frames, threads=1), our_poses(frames, threads=2)
    print(f"{np.count_nonzero(one != two)} pose entries differ between 1 and 2 threads (allowed 0)")
    assert np.array_equal(one, two)


def test_a_yaml_config_needs_neither_pyyaml_nor_kiss_icp(tmp_path, monkeypatch):
    yaml_file = tmp_path / "kiss.yaml"
    yaml_file.write_text("out_dir: results\ndata:\n  max_range: 60.0\nmapping:\n  voxel_size: null\n"
                         "  max_points_per_voxel: 10\nregistration:\n  max_num_threads: 1\n")
    want = kiss_odom.KissICP({"data": {"max_range": 60.0}, "runtime": {"threads": 1},
                              "mapping": {"max_points_per_voxel": 10, "voxel_size": 0.6}}).settings
    # Without PyYAML (kiss-icp's own loader would end the interpreter), then without kiss-icp.
    for missing in (["yaml"], ["yaml", "kiss_icp", "kiss_icp.config"]):
        for name in missing:
            monkeypatch.setitem(sys.modules, name, None)
        got = kiss_odom.KissICP(yaml_file).settings
        print(f"without {missing}: {got['data']}, {got['mapping']}")
        assert got == want


def test_nan_and_inf_settings_are_value_errors_naming_the_setting(tmp_path):
    with pytest.raises(ValueError, match=r"data\.max_range = nan: not a finite number"):
        kiss_odom.KissICP({"data": {"max_range": float("nan")}})
    with pytest.raises(ValueError, match=r"registration\.plane_gate = inf"):
        kiss_odom.KissICP({"registration": {"plane_gate": float("inf")}})
    for name, text in (("nan.yaml", "data:\n  min_range: .nan\n"),
                       ("inf.toml", "[data]\nmin_range = inf\n")):
        path = tmp_path / name
        path.write_text(text)
        with pytest.raises(ValueError, match=r"data\.min_range = (nan|inf): not a finite number"):
            kiss_odom.KissICP(path)
