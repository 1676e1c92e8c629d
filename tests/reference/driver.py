#!/usr/bin/env python3
"""Drive the reference kiss-icp 1.3.0 (C++ through pybind) from files, for cross-checks.

kiss-odom checks itself against the reference stage by stage and end to end. This driver is the
only place that talks to the reference: every command reads its inputs from files, runs one
reference entry point, and writes the outputs to files. `kiss-odom-dev crosscheck` calls it, and
`gen_golden.py` imports it to produce the committed goldens under `fixtures/golden/`.

    python driver.py <command> [options]      (python: a venv made from requirements.txt)

Commands
--------
pipeline     KissICP.register_frame over a sequence; writes LiDAR-frame poses (KITTI 3x4 text,
             full precision) and a JSON side file with per-frame sigma and timing.
               --dataset DIR --format kitti|generic [--frames A:B] [--threads N]
               [--deskew|--no-deskew] [--max-range R] [--min-range R] [--voxel-size V]
               [--max-points-per-voxel N] [--bin-layout f32x4|f32x3|f64x3|f64x4] --out poses.txt [--side side.json]
             kitti:   DIR is a sequence folder (DIR/velodyne/NNNNNN.bin, f32 x y z i); every
                      scan gets the reference's `_correct_kitti_scan`, as its KITTI loader does;
                      no per-point timestamps.
             generic: DIR/velodyne/*.bin or DIR/*.bin (natural order; layout --bin-layout,
                      default f32x4 as the reference's generic loader reads it), optional
                      per-point times DIR/timestamps/<stem>.bin (f64, one per point).
             All frames in the range are read before the first register_frame; the side file's
             `seconds` time only register_frame itself.
preprocess   _Preprocessor._preprocess: deskew (with --timestamps and --motion) and crop.
               --points P [--timestamps T] [--motion POSE] [--min-range R] [--max-range R]
               [--deskew|--no-deskew] [--threads N] --out OUT
deskew       preprocess with deskew on and no crop (min range -1, max range 1e300), so the
             output has one point per finite input point, in input order.
               --points P --timestamps T --motion POSE [--threads N] --out OUT
correct-kitti  _correct_kitti_scan.  --points P --out OUT
downsample   _voxel_down_sample (first point per voxel, robin-map bucket order).
               --points P --voxel V --out OUT
map          _VoxelHashMap: apply operations in the order given, then dump `_point_cloud()`.
               [--voxel-size 1] [--max-distance 100] [--max-points-per-voxel 20]
               {--update P POSE | --add P | --remove ORIGIN}... --out OUT
register     _Registration._align_points_to_map once; the map is built with `_add_points`
             (or `_update` when --map-pose is given).
               --map-points M [--map-pose POSE] [map options as above] --points P
               --initial-guess POSE (--sigma S | --max-corr-distance D --kernel K)
               [--max-iterations 500] [--convergence 1e-4] [--threads N] --out pose.json
correspondences  The reference's GetClosestNeighbor is not bound to Python. This command
             reconstructs it (a literal numpy port over the reference map's own contents, see
             `closest_neighbors`) and validates the reconstruction against the C++: a single
             Gauss-Newton iteration built from the reconstructed pairs must reproduce the
             reference's `_align_points_to_map` with max_num_iterations=1 to rounding, while any
             one-pair change would move that pose by far more (reported as the margin).
               --map-points M [--map-pose POSE] [map options] --queries Q --max-corr-distance D
               [--kernel K] [--threads N] --out pairs.json [--out-map cloud]
             pairs.json: `index` into the dumped map (-1: none), `distance` of the nearest
             candidate before the threshold (null: none), `validation` (see above).
threshold    _AdaptiveThreshold: sigma before the first and after every model deviation.
               --deviations D [--initial-threshold 2] [--min-motion 0.1] [--max-range 100]
               --out OUT
info         Versions of the reference and numpy, as JSON on stdout.
batch        Several of the commands above in one process, in order (saves the interpreter and
             import start-up of each): --commands FILE, a JSON list of argument lists, e.g.
             [["downsample", "--points", "a.f64", "--voxel", "0.5", "--out", "b.f64"], ...].
             The first command that builds a Preprocessor or Registration fixes the reference's
             thread count for the whole batch (see Threads).
bench        KissICP.register_frame timed on preloaded frames, for `kiss-odom-dev bench`.
               (--frames-dir DIR | --dataset DIR --format kitti|generic [--frames A:B]
               [--bin-layout L]) [--max-range R] [--min-range R] [--voxel-size V]
               [--deskew|--no-deskew] [--threads N] (--serve | [--repeats 3] --out results.json)
             --frames-dir DIR holds frames already loaded by kiss-odom (see `load_frames_dir`),
             so both implementations time the same bytes; --dataset loads as `pipeline` does.
             Every run builds a fresh KissICP over the frames in memory and times only
             register_frame; before it, the peak RSS counter is reset (Linux
             /proc/self/clear_refs), so each run reports its own peak. A run with map stats also
             counts the local map's voxels after every frame, outside the timed calls (the
             reference allocates max_points_per_voxel points per voxel it creates).
             --serve: one JSON line {"ready": ...} once the frames are loaded, then one JSON
             request per input line ({"map_stats": bool, "poses": bool}) answered by one JSON
             line (see `bench_run`), until end of input. kiss-odom uses it to alternate runs.

File formats
------------
points       .npy (float array, N x 3 or N x >=3: first three columns used) or raw little-endian
             f64, N x 3 (any other extension). Outputs use the same rule by extension.
scalars      (timestamps, sigmas) .npy or raw little-endian f64; `.json` for outputs.
POSE         12 or 16 numbers, row-major (3x4 or 4x4), inline ("1 0 0 0 ...", commas allowed)
             or `@FILE` (text with 12/16 numbers, `.npy`, or `.json` holding a nested list).
             The rotation must be orthonormal to 1e-10 (Sophus aborts otherwise; the driver
             refuses such poses with a message instead), so pass full-precision poses.
ORIGIN       3 numbers, inline or `@FILE`.
deviations   .npy (N x 4 x 4 or N x 16) or raw little-endian f64 N x 16 (row-major 4x4).
JSON floats are written with repr(), which round-trips float64 exactly.

Threads: the reference sets TBB's max_allowed_parallelism once per process, from the first
Preprocessor or Registration constructed (0 = all cores). With more than one thread its data
association and reductions run in a nondeterministic order, so results vary at rounding level
from run to run; use --threads 1 for bit-reproducible outputs (the default here is 1).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import kiss_icp
from kiss_icp.pybind import kiss_icp_pybind as kp

# The 27 voxel shifts in the order of the reference's VoxelHashMap.cpp: the order decides which
# of two equidistant neighbours in different voxels wins.
VOXEL_SHIFTS = np.array(
    [
        [0, 0, 0], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1],
        [1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0], [1, 0, 1], [1, 0, -1], [-1, 0, 1],
        [-1, 0, -1], [0, 1, 1], [0, 1, -1], [0, -1, 1], [0, -1, -1], [1, 1, 1], [1, 1, -1],
        [1, -1, 1], [1, -1, -1], [-1, 1, 1], [-1, 1, -1], [-1, -1, 1], [-1, -1, -1],
    ],
    dtype=np.int64,
)  # fmt: skip


# ----------------------------------------------------------------------------------------------
# File formats


def load_points(path: str | Path) -> np.ndarray:
    """N x 3 float64 points from `.npy` or raw little-endian f64."""
    path = Path(path)
    if path.suffix == ".npy":
        a = np.load(path)
        if a.ndim != 2 or a.shape[1] < 3:
            raise SystemExit(f"{path}: expected an N x 3 array, got shape {a.shape}")
        return np.ascontiguousarray(a[:, :3], dtype=np.float64)
    raw = np.fromfile(path, dtype="<f8")
    if raw.size % 3:
        raise SystemExit(f"{path}: {raw.size} doubles is not a whole number of points")
    return raw.reshape(-1, 3).astype(np.float64)


def load_scalars(path: str | Path) -> np.ndarray:
    """A 1-D float64 array from `.npy` or raw little-endian f64."""
    path = Path(path)
    if path.suffix == ".npy":
        return np.load(path).astype(np.float64).ravel()
    return np.fromfile(path, dtype="<f8").astype(np.float64)


def save_array(path: str | Path, a: np.ndarray) -> None:
    """Writes `a` as `.npy`, as JSON (`{"values": ...}`) or as raw little-endian bytes."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".npy":
        np.save(path, a)
    elif path.suffix == ".json":
        write_json(path, {"values": a.tolist()})
    else:
        a.astype(a.dtype.newbyteorder("<")).tofile(path)


def write_json(path: str | Path, obj) -> None:
    # json.dumps writes floats with repr(), which round-trips float64 exactly.
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(obj, indent=1) + "\n")


def _numbers(spec: str, counts: tuple[int, ...], what: str) -> np.ndarray:
    if spec.startswith("@"):
        path = Path(spec[1:])
        if path.suffix == ".npy":
            values = np.load(path).astype(np.float64).ravel()
        elif path.suffix == ".json":
            data = json.loads(path.read_text())
            if isinstance(data, dict):
                raise SystemExit(f"{path}: expected a JSON list of numbers (nested allowed)")
            values = np.asarray(data, dtype=np.float64).ravel()
        else:
            text = path.read_text()
            lines = [ln.split("#")[0] for ln in text.splitlines()]
            values = np.array(" ".join(lines).replace(",", " ").split(), dtype=np.float64)
    else:
        values = np.array(spec.replace(",", " ").split(), dtype=np.float64)
    if values.size not in counts:
        raise SystemExit(f"{what}: expected {' or '.join(map(str, counts))} numbers, got {values.size}")
    return values


def check_pose(pose: np.ndarray, what: str = "pose") -> np.ndarray:
    """Refuses a rotation Sophus's SO3 constructor would abort on: `|R^T R - I| >= 1e-10`
    (Frobenius) or `det R <= 0`."""
    pose = np.asarray(pose, dtype=np.float64)
    r = pose[:3, :3]
    off = float(np.linalg.norm(r.T @ r - np.eye(3)))
    if not (off < 1e-10 and np.linalg.det(r) > 0 and np.isfinite(pose).all()):
        raise SystemExit(
            f"{what}: not a rotation to 1e-10 (|R^T R - I| = {off:.1e}); the reference "
            "(Sophus) would abort. Pass full-precision poses."
        )
    return pose


def parse_pose(spec: str) -> np.ndarray:
    """A 4x4 pose from 12 (3x4) or 16 (4x4) row-major numbers, inline or `@FILE`."""
    v = _numbers(spec, (12, 16), "pose")
    pose = np.eye(4)
    pose[: v.size // 4] = v.reshape(-1, 4)
    return check_pose(pose)


def parse_origin(spec: str) -> np.ndarray:
    return _numbers(spec, (3,), "origin")


def load_deviations(path: str | Path) -> np.ndarray:
    path = Path(path)
    a = np.load(path) if path.suffix == ".npy" else np.fromfile(path, dtype="<f8")
    a = np.asarray(a, dtype=np.float64)
    if a.size % 16:
        raise SystemExit(f"{path}: {a.size} doubles is not a whole number of 4x4 matrices")
    return a.reshape(-1, 4, 4)


def vec3(points: np.ndarray):
    return kp._Vector3dVector(np.ascontiguousarray(points, dtype=np.float64))


# ----------------------------------------------------------------------------------------------
# Stages


def preprocess(points, timestamps, motion, min_range, max_range, deskew=True, threads=1):
    check_pose(np.asarray(motion, dtype=np.float64), "relative motion")
    pre = kp._Preprocessor(float(max_range), float(min_range), bool(deskew), int(threads))
    stamps = np.asarray(timestamps if timestamps is not None else [], dtype=np.float64).ravel()
    return np.asarray(pre._preprocess(vec3(points), stamps, np.asarray(motion, dtype=np.float64)))


def deskew(points, timestamps, motion, threads=1):
    """Deskewing alone: the range test `-1 < |p| < 1e300` keeps every finite point."""
    return preprocess(points, timestamps, motion, -1.0, 1e300, True, threads)


def correct_kitti(points):
    return np.asarray(kp._correct_kitti_scan(vec3(points)))


def downsample(points, voxel):
    return np.asarray(kp._voxel_down_sample(vec3(points), float(voxel)))


def new_map(voxel_size=1.0, max_distance=100.0, max_points_per_voxel=20):
    return kp._VoxelHashMap(float(voxel_size), float(max_distance), int(max_points_per_voxel))


def map_cloud(voxel_map) -> np.ndarray:
    """The map's points: voxel by voxel (robin-map bucket order), insertion order within one."""
    return np.asarray(voxel_map._point_cloud()).reshape(-1, 3)


def register(voxel_map, points, initial_guess, max_distance, kernel,
             max_iterations=500, convergence=1e-4, threads=1) -> np.ndarray:  # fmt: skip
    check_pose(initial_guess, "initial guess")
    reg = kp._Registration(int(max_iterations), float(convergence), int(threads))
    return np.asarray(
        reg._align_points_to_map(
            vec3(points), voxel_map, np.asarray(initial_guess, dtype=np.float64),
            float(max_distance), float(kernel),
        )
    )  # fmt: skip


def thresholds(deviations, initial_threshold=2.0, min_motion=0.1, max_range=100.0) -> np.ndarray:
    """Sigma before the first deviation and after each one (len(deviations) + 1 values)."""
    th = kp._AdaptiveThreshold(float(initial_threshold), float(min_motion), float(max_range))
    out = [th._compute_threshold()]
    for dev in deviations:
        check_pose(dev, "model deviation")
        th._update_model_deviation(np.asarray(dev, dtype=np.float64))
        out.append(th._compute_threshold())
    return np.array(out)


# ----------------------------------------------------------------------------------------------
# Correspondences: a reconstruction of GetClosestNeighbor, validated through registration


def _norms(d: np.ndarray) -> np.ndarray:
    # Eigen's norm() of a Vector3d: sqrt((x*x + y*y) + z*z), in that order.
    return np.sqrt((d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2])


def voxel_contents(cloud: np.ndarray, voxel_size: float) -> dict:
    """Voxel key -> indices into `cloud`, in insertion order.

    `_point_cloud()` writes each voxel's points contiguously and in insertion order, so grouping
    consecutive points by voxel recovers the map exactly.
    """
    keys = np.floor(cloud / voxel_size).astype(np.int64)
    voxels: dict = {}
    prev = None
    for i, k in enumerate(map(tuple, keys)):
        if k in voxels and k != prev:
            raise AssertionError(f"voxel {k} is not contiguous in the dumped cloud")
        voxels.setdefault(k, []).append(i)
        prev = k
    return {k: np.array(v) for k, v in voxels.items()}


def closest_neighbors(cloud, voxel_size, queries, max_distance):
    """Literal port of the reference's `GetClosestNeighbor` plus `DataAssociation`'s test.

    For each query: visit the 27 voxels in the reference's order; in each, take the first point
    of minimal norm (std::min_element with `<`, insertion order); it replaces the best so far
    only if strictly closer; the pair counts if `distance < max_distance`.

    Returns, per query, indices into `cloud`: `index` (the pair's target, -1 when rejected),
    `nearest` (the search result before the threshold, -1 for an empty neighbourhood) and
    `runner` (the closest other candidate of the 27 voxels, -1 if none), with the distances
    `nearest_d` and `runner_d` (inf when absent).
    """
    voxels = voxel_contents(cloud, voxel_size)
    n = len(queries)
    nearest = np.full(n, -1, dtype=np.int64)
    nearest_d = np.full(n, np.inf)
    runner = np.full(n, -1, dtype=np.int64)
    runner_d = np.full(n, np.inf)
    keys = np.floor(queries / voxel_size).astype(np.int64)
    for qi in range(n):
        q = queries[qi]
        closest, closest_d = -1, np.finfo(np.float64).max
        cand_i, cand_d = [], []
        for s in VOXEL_SHIFTS:
            members = voxels.get(tuple(keys[qi] + s))
            if members is None:
                continue
            d = _norms(cloud[members] - q)
            j = int(np.argmin(d))  # the first of equal minima, as std::min_element
            if d[j] < closest_d:
                closest, closest_d = int(members[j]), float(d[j])
            cand_i.append(members)
            cand_d.append(d)
        if closest < 0:
            continue
        nearest[qi], nearest_d[qi] = closest, closest_d
        ci, cd = np.concatenate(cand_i), np.concatenate(cand_d)
        others = ci != closest
        if others.any():
            k = int(np.argmin(np.where(others, cd, np.inf)))
            runner[qi], runner_d[qi] = int(ci[k]), float(cd[k])
    index = np.where(nearest_d < max_distance, nearest, -1)
    return index, nearest, nearest_d, runner, runner_d


def _so3_exp(omega: np.ndarray) -> np.ndarray:
    # Sophus SO3::exp (quaternion form, small-angle branch included), as a rotation matrix.
    eps = np.finfo(np.float64).eps
    theta_sq = float(omega @ omega)
    if theta_sq < eps * eps:
        imag = 0.5 - theta_sq / 48.0 + theta_sq * theta_sq / 3840.0
        real = 1.0 - theta_sq / 8.0 + theta_sq * theta_sq / 384.0
    else:
        theta = np.sqrt(theta_sq)
        imag, real = np.sin(0.5 * theta) / theta, np.cos(0.5 * theta)
    w, (x, y, z) = real, imag * omega
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _hat(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def se3_exp(dx: np.ndarray) -> np.ndarray:
    """Sophus SE3::exp of the twist [upsilon; omega] as a 4x4 matrix."""
    upsilon, omega = dx[:3], dx[3:]
    theta = np.linalg.norm(omega)
    big = _hat(omega)
    if theta < np.finfo(np.float64).eps:
        v = np.eye(3) + 0.5 * big
    else:
        v = (np.eye(3) + (1 - np.cos(theta)) / theta**2 * big
             + (theta - np.sin(theta)) / theta**3 * big @ big)  # fmt: skip
    pose = np.eye(4)
    pose[:3, :3] = _so3_exp(omega)
    pose[:3, 3] = v @ upsilon
    return pose


def _pair_systems(sources, targets, kernel):
    """Per-pair J^T W J (n x 6 x 6) and J^T W r (n x 6) of the reference's BuildLinearSystem."""
    r = sources - targets
    w = kernel**2 / (kernel + np.einsum("ij,ij->i", r, r)) ** 2
    n = len(sources)
    jac = np.zeros((n, 3, 6))
    jac[:, :, :3] = np.eye(3)
    s = sources
    jac[:, 0, 4], jac[:, 0, 5] = s[:, 2], -s[:, 1]  # -hat(s)
    jac[:, 1, 3], jac[:, 1, 5] = -s[:, 2], s[:, 0]
    jac[:, 2, 3], jac[:, 2, 4] = s[:, 1], -s[:, 0]
    jtj = np.einsum("nki,n,nkj->nij", jac, w, jac)
    jtr = np.einsum("nki,n,nk->ni", jac, w, r)
    return jtj, jtr


def pose_difference(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """(largest translation component difference in m, angle of a^-1 b in rad)."""
    dt = float(np.max(np.abs(a[:3, 3] - b[:3, 3])))
    r = a[:3, :3].T @ b[:3, :3]
    # atan2 of the skew part keeps tiny angles accurate where arccos of the trace does not.
    s = np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2
    return dt, float(np.arctan2(s, (np.trace(r) - 1) / 2))


def validate_pairs(voxel_map, cloud, queries, pairs, max_distance, kernel, threads=1) -> dict:
    """Checks reconstructed pairs against the C++ through one registration iteration.

    `pairs` is the tuple `closest_neighbors` returns. The reference runs one ICP iteration from
    the identity over `queries` (max_num_iterations=1); the same Gauss-Newton step is rebuilt in
    numpy from the reconstructed pairs. Returns their disagreement and the detection margin:
    the smallest twist change (max abs component of dx) that any single-pair alternative would
    cause: an accepted pair dropped, an accepted pair with the runner-up candidate (if that is
    within the threshold) as target, or a rejected query's nearest candidate accepted.
    """
    index, nearest, _, runner, runner_d = pairs
    ref = register(voxel_map, queries, np.eye(4), max_distance, kernel, 1, 0.0, threads)

    used = np.flatnonzero(index >= 0)
    jtj, jtr = _pair_systems(queries[used], cloud[index[used]], kernel)
    h, g = jtj.sum(0), jtr.sum(0)
    dx0 = np.linalg.solve(h, -g)
    agree = pose_difference(ref, se3_exp(dx0))

    d_h, d_g = [-jtj], [-jtr]  # an accepted pair dropped
    alt = used[(runner[used] >= 0) & (runner_d[used] < max_distance)]
    if len(alt):  # the runner-up instead
        ah, ag = _pair_systems(queries[alt], cloud[runner[alt]], kernel)
        pos = np.searchsorted(used, alt)
        d_h.append(ah - jtj[pos])
        d_g.append(ag - jtr[pos])
    rej = np.flatnonzero((index < 0) & (nearest >= 0))
    if len(rej):  # a rejected nearest candidate accepted
        ah, ag = _pair_systems(queries[rej], cloud[nearest[rej]], kernel)
        d_h.append(ah)
        d_g.append(ag)
    d_h, d_g = np.concatenate(d_h), np.concatenate(d_g)
    dxs = np.linalg.solve(h[None] + d_h, -(g[None] + d_g)[..., None])[..., 0]
    base = se3_exp(dx0)
    change = [max(pose_difference(base, se3_exp(dx))) for dx in dxs]
    return {
        "queries": int(len(queries)),
        "pairs": int(len(used)),
        "max_distance": float(max_distance),
        "kernel": float(kernel),
        "translation_disagreement_m": agree[0],
        "rotation_disagreement_rad": agree[1],
        "single_pair_alternatives": int(len(change)),
        "smallest_single_pair_change": float(min(change)),
    }


def correspondences(voxel_map, queries, max_distance, kernel, voxel_size, threads=1):
    """Reconstructed, validated pairs: (cloud, closest_neighbors tuple, validation report)."""
    cloud = map_cloud(voxel_map)
    pairs = closest_neighbors(cloud, voxel_size, queries, max_distance)
    report = validate_pairs(voxel_map, cloud, queries, pairs, max_distance, kernel, threads)
    return cloud, pairs, report


# ----------------------------------------------------------------------------------------------
# Datasets and the whole pipeline


def _natural_key(name: str):
    import re

    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


BIN_LAYOUTS = {"f32x4": ("<f4", 4), "f32x3": ("<f4", 3), "f64x3": ("<f8", 3), "f64x4": ("<f8", 4)}


def read_bin(path: Path, layout: str) -> np.ndarray:
    dtype, cols = BIN_LAYOUTS[layout]
    raw = np.fromfile(path, dtype=dtype)
    if raw.size % cols:
        raise SystemExit(f"{path}: not a whole number of {layout} points")
    return raw.reshape(-1, cols)[:, :3].astype(np.float64)


def load_frames(dataset: Path, fmt: str, frames: slice, layout: str):
    """[(name, points, timestamps)] of the selected frames, all read up front."""
    if fmt == "kitti":
        files = sorted((dataset / "velodyne").glob("*.bin"))
    else:
        folder = dataset / "velodyne" if (dataset / "velodyne").is_dir() else dataset
        files = sorted(
            (p for p in folder.iterdir() if p.suffix in (".bin", ".npy")),
            key=lambda p: _natural_key(p.name),
        )
    if not files:
        raise SystemExit(f"no frames found in {dataset}")
    out = []
    for path in files[frames]:
        if fmt == "kitti":
            # As KITTIOdometryDataset.read_point_cloud: f32 -> f64, then the scan correction.
            points = correct_kitti(read_bin(path, "f32x4"))
            stamps = np.array([])
        else:
            points = np.load(path)[:, :3].astype(np.float64) if path.suffix == ".npy" else read_bin(path, layout)
            tfile = dataset / "timestamps" / (path.stem + ".bin")
            stamps = np.fromfile(tfile, dtype="<f8") if tfile.exists() else np.array([])
            if stamps.size and stamps.size != len(points):
                raise SystemExit(f"{tfile}: {stamps.size} times for {len(points)} points")
        out.append((path.name, points, stamps))
    return out


def parse_frames(spec: str | None) -> slice:
    if not spec:
        return slice(None)
    a, _, b = spec.partition(":")
    return slice(int(a) if a else None, int(b) if b else None)


def run_pipeline(frames, max_range=100.0, min_range=0.0, deskew_on=True, voxel_size=None,
                 threads=1, max_points_per_voxel=20):  # fmt: skip
    """Runs KissICP over preloaded frames; returns poses (n x 4 x 4), sigmas, seconds, config."""
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP

    config = load_config(None)
    config.data.max_range = float(max_range)
    config.data.min_range = float(min_range)
    config.data.deskew = bool(deskew_on)
    config.mapping.voxel_size = float(voxel_size) if voxel_size else float(max_range) / 100.0
    config.mapping.max_points_per_voxel = int(max_points_per_voxel)
    config.registration.max_num_threads = int(threads)
    odom = KissICP(config)
    poses, sigmas, seconds = [], [], []
    for _, points, stamps in frames:
        sigmas.append(float(odom.adaptive_threshold.get_threshold()))
        t0 = time.perf_counter()
        odom.register_frame(points, stamps)
        seconds.append(time.perf_counter() - t0)
        poses.append(np.array(odom.last_pose))
    return np.array(poses), sigmas, seconds, config


def write_kitti_poses(path: str | Path, poses: np.ndarray) -> None:
    lines = [" ".join(repr(float(v)) for v in p[:3].ravel()) for p in poses]
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text("\n".join(lines) + "\n")


def versions() -> dict:
    return {
        "kiss_icp": kiss_icp.__version__,
        "numpy": np.__version__,
        "python": sys.version.split()[0],
    }


# ----------------------------------------------------------------------------------------------
# Benchmark


def load_frames_dir(folder: Path):
    """Frames written by `kiss-odom-dev bench`: `frames.json` ({"frames": [{"name", "points",
    "stamps"}]}) with the counts, `points.f64` (all points, x y z, little-endian f64) and
    `stamps.f64` (all per-point times, concatenated), in frame order. Same tuples as
    `load_frames`."""
    index = json.loads((folder / "frames.json").read_text())["frames"]
    points = np.fromfile(folder / "points.f64", dtype="<f8").reshape(-1, 3)
    stamps = np.fromfile(folder / "stamps.f64", dtype="<f8")
    out, p, t = [], 0, 0
    for f in index:
        n, m = int(f["points"]), int(f["stamps"])
        out.append((f["name"], np.ascontiguousarray(points[p : p + n]), stamps[t : t + m].copy()))
        p, t = p + n, t + m
    if p != len(points) or t != len(stamps):
        raise SystemExit(f"{folder}: frames.json does not match points.f64/stamps.f64")
    return out


def _proc_status_kib(field: str) -> int | None:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak_rss() -> bool:
    """Resets VmHWM to the current RSS (Linux >= 4.0); False where that is not possible."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


def map_voxels(local_map, voxel_size: float) -> tuple[int, int]:
    """(occupied voxels, points) of a kiss_icp VoxelHashMap, from its point cloud."""
    cloud = local_map.point_cloud().reshape(-1, 3)
    if not len(cloud):
        return 0, 0
    keys = np.floor(cloud / voxel_size).astype(np.int64)
    return int(len(np.unique(keys, axis=0))), int(len(cloud))


def bench_run(frames, settings: dict, map_stats=False, poses=False) -> dict:
    """One timed run of a fresh KissICP over preloaded frames.

    Returns `seconds` (register_frame per frame), `rss_before_bytes` (RSS when the run starts,
    frames loaded), `peak_rss_bytes` (peak during the run; null where it cannot be reset), and
    with `map_stats` the peak map voxels and points plus the time the numpy -> std::vector
    conversion of each input frame takes (`binding_seconds`, a lower bound of the Python
    bindings' share of `seconds`); with `poses`, the 4x4 poses (row-major, 16 numbers each).
    """
    from kiss_icp.config import load_config
    from kiss_icp.kiss_icp import KissICP

    config = load_config(None)
    config.data.max_range = float(settings["max_range"])
    config.data.min_range = float(settings["min_range"])
    config.data.deskew = bool(settings["deskew"])
    voxel = settings["voxel_size"] or float(settings["max_range"]) / 100.0
    config.mapping.voxel_size = float(voxel)
    config.registration.max_num_threads = int(settings["threads"])
    odom = KissICP(config)
    reset = _reset_peak_rss()
    rss_before = _proc_status_kib("VmRSS")
    seconds, out_poses, peak_voxels, peak_points, binding = [], [], 0, 0, []
    for _, points, stamps in frames:
        t0 = time.perf_counter()
        odom.register_frame(points, stamps)
        seconds.append(time.perf_counter() - t0)
        if poses:
            out_poses.append(np.asarray(odom.last_pose).ravel().tolist())
        if map_stats:
            v, n = map_voxels(odom.local_map, voxel)
            peak_voxels, peak_points = max(peak_voxels, v), max(peak_points, n)
            t0 = time.perf_counter()
            kp._Vector3dVector(points)
            binding.append(time.perf_counter() - t0)
    peak = _proc_status_kib("VmHWM") if reset else None
    res = {
        "seconds": seconds,
        "rss_before_bytes": rss_before * 1024 if rss_before is not None else None,
        "peak_rss_bytes": peak * 1024 if peak is not None else None,
    }
    if map_stats:
        res["map_voxels_peak"] = peak_voxels
        res["map_points_peak"] = peak_points
        res["binding_seconds"] = binding
    if poses:
        res["poses"] = out_poses
    return res


def bench_frames(a):
    if a.frames_dir is not None:
        return load_frames_dir(a.frames_dir)
    if a.dataset is None or a.format is None:
        raise SystemExit("bench: give --frames-dir, or --dataset and --format")
    return load_frames(a.dataset, a.format, parse_frames(a.frames), a.bin_layout)


def bench_settings(a) -> dict:
    return {
        "max_range": a.max_range,
        "min_range": a.min_range,
        "voxel_size": a.voxel_size,
        "deskew": a.deskew,
        "threads": a.threads,
    }


def bench_serve(frames, settings: dict, inp=sys.stdin, out=sys.stdout) -> None:
    """The line protocol of `bench --serve` (see the module docstring)."""
    ready = {
        "ready": True,
        "frames": len(frames),
        "points": int(sum(len(p) for _, p, _ in frames)),
        "versions": versions(),
        "settings": settings,
    }
    print(json.dumps(ready), file=out, flush=True)
    for line in inp:
        if not line.strip():
            continue
        req = json.loads(line)
        res = bench_run(frames, settings, bool(req.get("map_stats")), bool(req.get("poses")))
        print(json.dumps(res), file=out, flush=True)


# ----------------------------------------------------------------------------------------------
# Command line


def _add_threads(p):
    p.add_argument("--threads", type=int, default=1,
                   help="reference threads (0: all cores; default 1, deterministic)")  # fmt: skip


def _add_deskew(p):
    p.add_argument("--deskew", dest="deskew", action="store_true", default=True)
    p.add_argument("--no-deskew", dest="deskew", action="store_false")


def _add_map_options(p):
    p.add_argument("--voxel-size", type=float, default=1.0)
    p.add_argument("--max-distance", dest="map_max_distance", type=float, default=100.0,
                   help="map pruning distance (the reference's max_range)")  # fmt: skip
    p.add_argument("--max-points-per-voxel", type=int, default=20)


class _MapOp(argparse.Action):
    """Collects --update/--add/--remove in command-line order."""

    def __call__(self, parser, namespace, values, option_string=None):
        ops = getattr(namespace, "ops", None) or []
        ops.append((option_string.lstrip("-"), values))
        namespace.ops = ops


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="driver.py", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    sub = ap.add_subparsers(dest="command", required=True)

    p = sub.add_parser("pipeline", help="KissICP over a sequence -> poses + side JSON")
    p.add_argument("--dataset", required=True, type=Path)
    p.add_argument("--format", choices=["kitti", "generic"], required=True)
    p.add_argument("--frames", help="A:B, Python slice of the sorted frames (B exclusive)")
    p.add_argument("--max-range", type=float, default=100.0)
    p.add_argument("--min-range", type=float, default=0.0)
    p.add_argument("--voxel-size", type=float, default=None, help="default max_range / 100")
    p.add_argument("--max-points-per-voxel", type=int, default=20)
    p.add_argument("--bin-layout", choices=sorted(BIN_LAYOUTS), default="f32x4")
    _add_deskew(p)
    _add_threads(p)
    p.add_argument("--out", required=True, type=Path, help="poses, KITTI 3x4 text, LiDAR frame")
    p.add_argument("--side", type=Path, help="JSON side file (default: OUT with .json)")

    p = sub.add_parser("preprocess", help="deskew + crop")
    p.add_argument("--points", required=True)
    p.add_argument("--timestamps")
    p.add_argument("--motion", default="1 0 0 0 0 1 0 0 0 0 1 0")
    p.add_argument("--min-range", type=float, default=0.0)
    p.add_argument("--max-range", type=float, default=100.0)
    _add_deskew(p)
    _add_threads(p)
    p.add_argument("--out", required=True)

    p = sub.add_parser("deskew", help="deskew only, one output point per finite input point")
    p.add_argument("--points", required=True)
    p.add_argument("--timestamps", required=True)
    p.add_argument("--motion", required=True)
    _add_threads(p)
    p.add_argument("--out", required=True)

    p = sub.add_parser("correct-kitti", help="the reference's KITTI scan correction")
    p.add_argument("--points", required=True)
    p.add_argument("--out", required=True)

    p = sub.add_parser("downsample", help="voxel downsampling")
    p.add_argument("--points", required=True)
    p.add_argument("--voxel", type=float, required=True)
    p.add_argument("--out", required=True)

    p = sub.add_parser("map", help="voxel hash map operations, then dump its points")
    _add_map_options(p)
    p.add_argument("--update", nargs=2, metavar=("POINTS", "POSE"), action=_MapOp)
    p.add_argument("--add", nargs=1, metavar="POINTS", action=_MapOp)
    p.add_argument("--remove", nargs=1, metavar="ORIGIN", action=_MapOp)
    p.add_argument("--out", required=True)

    p = sub.add_parser("register", help="one AlignPointsToMap")
    p.add_argument("--map-points", required=True)
    p.add_argument("--map-pose")
    _add_map_options(p)
    p.add_argument("--points", required=True)
    p.add_argument("--initial-guess", default="1 0 0 0 0 1 0 0 0 0 1 0")
    p.add_argument("--sigma", type=float, help="max distance 3 sigma, kernel sigma")
    p.add_argument("--max-corr-distance", type=float)
    p.add_argument("--kernel", type=float)
    p.add_argument("--max-iterations", type=int, default=500)
    p.add_argument("--convergence", type=float, default=1e-4)
    _add_threads(p)
    p.add_argument("--out", required=True)

    p = sub.add_parser("correspondences", help="reconstructed GetClosestNeighbor, validated")
    p.add_argument("--map-points", required=True)
    p.add_argument("--map-pose")
    _add_map_options(p)
    p.add_argument("--queries", required=True)
    p.add_argument("--max-corr-distance", type=float, required=True)
    p.add_argument("--kernel", type=float, help="kernel for the validation (default: D / 3)")
    _add_threads(p)
    p.add_argument("--out", required=True, help="JSON: index into the dumped map, distance")
    p.add_argument("--out-map", help="the dumped map cloud the indices refer to")

    p = sub.add_parser("threshold", help="adaptive threshold over model deviations")
    p.add_argument("--deviations", required=True)
    p.add_argument("--initial-threshold", type=float, default=2.0)
    p.add_argument("--min-motion", type=float, default=0.1)
    p.add_argument("--max-range", type=float, default=100.0)
    p.add_argument("--out", required=True)

    sub.add_parser("info", help="versions, as JSON")

    p = sub.add_parser("batch", help="several commands in one process")
    p.add_argument("--commands", required=True, type=Path,
                   help="JSON list of argument lists, run in order")  # fmt: skip

    p = sub.add_parser("bench", help="timed register_frame runs on preloaded frames")
    p.add_argument("--frames-dir", type=Path, help="frames written by kiss-odom-dev bench")
    p.add_argument("--dataset", type=Path)
    p.add_argument("--format", choices=["kitti", "generic"])
    p.add_argument("--frames", help="A:B, Python slice of the sorted frames (B exclusive)")
    p.add_argument("--bin-layout", choices=sorted(BIN_LAYOUTS), default="f32x4")
    p.add_argument("--max-range", type=float, default=100.0)
    p.add_argument("--min-range", type=float, default=0.0)
    p.add_argument("--voxel-size", type=float, default=None, help="default max_range / 100")
    _add_deskew(p)
    _add_threads(p)
    p.add_argument("--serve", action="store_true", help="line protocol on stdin/stdout")
    p.add_argument("--repeats", type=int, default=3, help="runs without --serve")
    p.add_argument("--out", type=Path, help="results JSON without --serve")
    return ap


def _build_map(a) -> object:
    m = new_map(a.voxel_size, a.map_max_distance, a.max_points_per_voxel)
    points = load_points(a.map_points)
    if a.map_pose:
        m._update(vec3(points), parse_pose(a.map_pose))
    else:
        m._add_points(vec3(points))
    return m


def main(argv=None) -> int:
    a = build_parser().parse_args(argv)
    if a.command == "pipeline":
        frames = load_frames(a.dataset, a.format, parse_frames(a.frames), a.bin_layout)
        poses, sigmas, seconds, config = run_pipeline(
            frames, a.max_range, a.min_range, a.deskew, a.voxel_size, a.threads,
            a.max_points_per_voxel,
        )
        write_kitti_poses(a.out, poses)
        side = a.side or a.out.with_suffix(".json")
        write_json(side, {
            "versions": versions(),
            "dataset": str(a.dataset),
            "format": a.format,
            "frames": a.frames or ":",
            "threads": a.threads,
            "config": config.model_dump(),
            "kitti_correction": a.format == "kitti",
            "per_frame": [
                {"file": name, "points": len(pts), "timestamps": int(st.size),
                 "sigma": s, "seconds": t}
                for (name, pts, st), s, t in zip(frames, sigmas, seconds)
            ],
            "total_seconds": sum(seconds),
        })  # fmt: skip
    elif a.command in ("preprocess", "deskew"):
        points = load_points(a.points)
        stamps = load_scalars(a.timestamps) if a.timestamps else None
        motion = parse_pose(a.motion)
        if a.command == "deskew":
            out = deskew(points, stamps, motion, a.threads)
        else:
            out = preprocess(points, stamps, motion, a.min_range, a.max_range, a.deskew, a.threads)
        save_array(a.out, out)
    elif a.command == "correct-kitti":
        save_array(a.out, correct_kitti(load_points(a.points)))
    elif a.command == "downsample":
        save_array(a.out, downsample(load_points(a.points), a.voxel))
    elif a.command == "map":
        m = new_map(a.voxel_size, a.map_max_distance, a.max_points_per_voxel)
        for op, values in getattr(a, "ops", None) or []:
            if op == "update":
                m._update(vec3(load_points(values[0])), parse_pose(values[1]))
            elif op == "add":
                m._add_points(vec3(load_points(values[0])))
            else:
                m._remove_far_away_points(parse_origin(values[0]))
        save_array(a.out, map_cloud(m))
    elif a.command == "register":
        if a.sigma is not None:
            dist, kernel = 3.0 * a.sigma, a.sigma
        elif a.max_corr_distance is not None and a.kernel is not None:
            dist, kernel = a.max_corr_distance, a.kernel
        else:
            raise SystemExit("register: give --sigma, or --max-corr-distance and --kernel")
        pose = register(_build_map(a), load_points(a.points), parse_pose(a.initial_guess),
                        dist, kernel, a.max_iterations, a.convergence, a.threads)  # fmt: skip
        write_json(a.out, {"pose": pose.tolist(), "max_distance": dist, "kernel": kernel})
    elif a.command == "correspondences":
        m = _build_map(a)
        kernel = a.kernel if a.kernel is not None else a.max_corr_distance / 3.0
        cloud, pairs, report = correspondences(
            m, load_points(a.queries), a.max_corr_distance, kernel, a.voxel_size, a.threads
        )
        if a.out_map:
            save_array(a.out_map, cloud)
        index, _, nearest_d = pairs[:3]
        write_json(a.out, {
            "index": index.tolist(),
            "distance": [d if np.isfinite(d) else None for d in nearest_d.tolist()],
            "validation": report,
        })  # fmt: skip
        print(json.dumps(report, indent=1), file=sys.stderr)
    elif a.command == "threshold":
        sig = thresholds(load_deviations(a.deviations), a.initial_threshold, a.min_motion,
                         a.max_range)  # fmt: skip
        save_array(a.out, sig)
    elif a.command == "info":
        print(json.dumps(versions()))
    elif a.command == "batch":
        commands = json.loads(a.commands.read_text())
        if not isinstance(commands, list) or not all(
            isinstance(c, list) and c and c[0] != "batch" and all(isinstance(x, str) for x in c)
            for c in commands
        ):
            raise SystemExit(f"{a.commands}: expected a JSON list of non-batch argument lists")
        for argv in commands:
            main(argv)
    elif a.command == "bench":
        frames = bench_frames(a)
        settings = bench_settings(a)
        if a.serve:
            bench_serve(frames, settings)
        else:
            if a.out is None:
                raise SystemExit("bench: give --out (or --serve)")
            runs = [bench_run(frames, settings, map_stats=(r == 0)) for r in range(a.repeats)]
            write_json(a.out, {"versions": versions(), "settings": settings, "runs": runs})
    return 0


if __name__ == "__main__":
    sys.exit(main())
