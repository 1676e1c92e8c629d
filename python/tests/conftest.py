"""Shared fixtures: where the repository, the data and the `kiss-odom` binary are, and the
generated sequences the tests share.

Environment (set by `.ci/run`; the defaults fit a checkout with `../shared` beside it):
- `KISS_ODOM_BIN`: the `kiss-odom` binary (default `target/release/kiss-odom`);
- `KISS_ODOM_DATA`: the shared data folder (default `../shared/data`).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
KITTI_SEQUENCES = ("01", "02", "04", "05")


def data_dir() -> Path:
    return Path(os.environ.get("KISS_ODOM_DATA", REPO.parent / "shared" / "data"))


def kitti_root() -> Path:
    root = data_dir() / "kitti-mini"
    if not root.is_dir():
        pytest.skip(f"SKIP: kitti-mini not found at {root}")
    return root


def binary() -> Path:
    path = Path(os.environ.get("KISS_ODOM_BIN", REPO / "target" / "release" / "kiss-odom"))
    if not path.is_file():
        pytest.skip(f"SKIP: no kiss-odom binary at {path} (cargo build --release -p kiss-odom)")
    return path


def kiss_odom(*args, check=True) -> subprocess.CompletedProcess:
    """Runs the `kiss-odom` binary."""
    return subprocess.run(
        [str(binary()), *map(str, args)], capture_output=True, text=True, check=check
    )


def read_kitti(path: Path) -> np.ndarray:
    """A KITTI pose file as Nx4x4 (text parsed with Python's float: exact for our files)."""
    rows = [list(map(float, line.split())) for line in Path(path).read_text().splitlines() if line]
    out = np.tile(np.eye(4), (len(rows), 1, 1))
    out[:, :3, :4] = np.array(rows).reshape(-1, 3, 4)
    return out


def kitti_frames(sequence: str):
    """The `.bin` scans of a kitti-mini sequence, Nx3 float64, with the KITTI correction
    applied as `kiss-odom run` applies it."""
    import kiss_odom

    folder = kitti_root() / "sequences" / sequence / "velodyne"
    for f in sorted(folder.glob("*.bin")):
        pts = np.fromfile(f, dtype=np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
        yield kiss_odom.correct_kitti_scan(pts)


@pytest.fixture(scope="session")
def generated(tmp_path_factory) -> Path:
    """A 100-frame simulated drive (`kiss-odom simulate --frames 100`), generic layout."""
    out = tmp_path_factory.mktemp("sim") / "urban"
    kiss_odom("simulate", "--out", out, "--frames", 100)
    return out


@pytest.fixture(scope="session")
def generated_short(tmp_path_factory) -> list:
    """Two small simulated sequences for the batch test: a fast drive long enough for KITTI's
    100 m segments (90 frames at 20-30 m/s) and a short corridor."""
    root = tmp_path_factory.mktemp("sim-short")
    out = []
    for name, seed, profile, frames in (("fast-s1", 1, "fast", 90), ("corridor-s3", 3, "corridor", 20)):
        kiss_odom("simulate", "--out", root / name, "--frames", frames, "--seed", seed,
                  "--profile", profile, "--beams", 32, "--columns", 512)
        out.append(root / name)
    return out
