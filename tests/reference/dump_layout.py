#!/usr/bin/env python3
"""Dump what kiss-icp 1.3.0's own dataloader reads from a dataset folder, for the layout tests.

    python dump_layout.py --loader mulran|nclt|ncd|helipr|boreas|nuscenes|apollo|kitti_raw \
        --data DIR --out OUT [--sequence S]... [--pipeline] [--other-frames N]

Each --sequence (none: the loader's default) is read into OUT/<S> (OUT/default without one),
the ones after the first for their first N frames only with --other-frames N:
  points_<i>.f64   frame i's points as the loader returns them, float64 little-endian, x y z
  stamps_<i>.f64   its per-point times as float64 (empty when the loader returns none)
  gt.f64           the loader's gt_poses, 16 float64 a pose, row-major
  pipeline.json    with --pipeline, for the first sequence only: kiss-icp's OdometryPipeline
                   run on the loader (default config), its poses and the metrics it prints
                   (kiss_icp_pipeline's figures)
and OUT/info.json says {"numpy": version, "float32_products": "fused" or "separate" (how this
numpy's BLAS rounds a float32 matrix product, which decides nuScenes' float32 ground truth),
"stand_ins": [modules replaced], "sequences": {S: {"frames": the loader's length, "dumped":
frames dumped}}}.

A loader's reading library that cannot be used here is replaced by a stand-in from
standins/ (open3d for Apollo's PCD, pyntcloud for Newer College's, which numpy 2 breaks, and
nuscenes-devkit's tables for nuScenes); info.json names each one used. Exits 3 with
"SKIP: reason" on stdout when a loader's dependency has no stand-in and cannot be imported
(scipy for nclt).
"""
import argparse
import importlib
import json
import sys
from pathlib import Path

import numpy as np

# The module each loader reads with, and whether standins/ has one for it.
NEEDS = {
    "nclt": ("scipy", False),
    "ncd": ("pyntcloud", True),
    "apollo": ("open3d", True),
    "nuscenes": ("nuscenes", True),
    "mulran": (None, False),
    "helipr": ("pyquaternion", False),
    "boreas": ("natsort", False),
    "kitti_raw": (None, False),
}
STANDINS = Path(__file__).resolve().parent / "standins"


def usable(module: str) -> bool:
    # pyntcloud 0.3 reads binary PCD with np.fromstring, which numpy 2 removed (asked first:
    # importing it takes seconds).
    if module == "pyntcloud" and int(np.__version__.split(".")[0]) >= 2:
        return False
    try:
        importlib.import_module(module)
    except Exception:  # an import error of any kind means: not usable here
        return False
    return True


def stand_in(module: str) -> None:
    for name in [n for n in sys.modules if n == module or n.startswith(module + ".")]:
        del sys.modules[name]
    sys.path.insert(0, str(STANDINS))
    importlib.import_module(module)


def float32_products() -> str:
    """How numpy's float32 `@` (BLAS sgemm) sums: `x x - (1 + 2^-11)` with `x = 1 + 2^-12` is
    2^-24 with a fused multiply-add and 0 with the product rounded first. Shaped as the
    loaders' `(4, 4) @ (n, 4, 4)`, so that the same kernel runs."""
    x = np.float32(1 + 2**-12)
    a = np.zeros((4, 4), np.float32)
    a[0, 0], a[0, 1] = -(1 + 2**-11), x
    b = np.zeros((2, 4, 4), np.float32)
    b[:, 0, 0], b[:, 1, 0] = 1, x
    return "fused" if (a @ b)[0, 0, 0] != 0 else "separate"


def dump(dataset, out: Path, frames: int) -> int:
    out.mkdir(parents=True, exist_ok=True)
    n = min(len(dataset), frames)
    for i in range(n):
        points, stamps = dataset[i]
        np.ascontiguousarray(points, dtype="<f8").tofile(out / f"points_{i}.f64")
        np.ascontiguousarray(np.asarray(stamps, dtype=np.float64), dtype="<f8").tofile(
            out / f"stamps_{i}.f64"
        )
    gt = np.asarray(dataset.gt_poses, dtype=np.float64).reshape(-1, 16)
    np.ascontiguousarray(gt, dtype="<f8").tofile(out / "gt.f64")
    return n


def pipeline(dataset, out: Path) -> None:
    from kiss_icp.pipeline import OdometryPipeline

    p = OdometryPipeline(dataset=dataset, config=None, visualize=False)
    p._run_pipeline()
    p._run_evaluation()
    # NaN (no 100 m segment for the KITTI errors) is written as null.
    metrics = {r.desc: float(r.value) for r in p.results}
    metrics = {k: (v if np.isfinite(v) else None) for k, v in metrics.items()}
    poses = np.asarray(p.poses, dtype=np.float64).reshape(-1, 16).tolist()
    (out / "pipeline.json").write_text(json.dumps({"metrics": metrics, "poses": poses}))


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--loader", required=True, choices=sorted(NEEDS))
    ap.add_argument("--data", required=True)
    ap.add_argument("--sequence", action="append", default=[])
    ap.add_argument("--out", required=True)
    ap.add_argument("--pipeline", action="store_true")
    ap.add_argument("--other-frames", type=int, default=None)
    a = ap.parse_args()
    need, has_stand_in = NEEDS[a.loader]
    stand_ins = []
    if need is not None and not usable(need):
        if not has_stand_in:
            print(f"SKIP: the {a.loader} loader needs {need}, which cannot be imported here")
            return 3
        stand_in(need)
        stand_ins.append(need)
    from kiss_icp.datasets import dataset_factory

    out = Path(a.out)
    sequences = {}
    for k, seq in enumerate(a.sequence or [None]):
        kwargs = {"sequence": seq} if seq is not None else {}
        dataset = dataset_factory(dataloader=a.loader, data_dir=Path(a.data), **kwargs)
        name = seq if seq is not None else "default"
        limit = a.other_frames if k > 0 and a.other_frames is not None else len(dataset)
        sequences[name] = {"frames": len(dataset), "dumped": dump(dataset, out / name, limit)}
        if a.pipeline and k == 0:
            pipeline(dataset, out / name)
    info = {
        "numpy": np.__version__,
        "float32_products": float32_products(),
        "stand_ins": stand_ins,
        "sequences": sequences,
    }
    (out / "info.json").write_text(json.dumps(info))
    return 0


if __name__ == "__main__":
    sys.exit(main())
